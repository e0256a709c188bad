/* dem_contact_list — the contacts of a step and their history, and the pair-property table.
 *
 * Contract: a contact is keyed by (sphere i, kind, j, aux); a dem_contacts list holds the
 * records ordered by sphere i, then by discovery order (deterministic: see dem_contact_pass.h).
 * The contact state is the current list, the previous step's list (the history the next pass
 * looks up by key) and, for both, the CSR index of each sphere's first record. The pair table
 * holds the effective properties (E*, G*, ζ, μ) of every sphere material against every wall
 * material, built once by dem_contact_state_prepare(); the per-contact R* and m* are filled in
 * by the inline lookups below. Storage grows on demand and is freed by the _free functions.
 */
#ifndef DEM_CONTACT_LIST_H
#define DEM_CONTACT_LIST_H

#include <math.h>

#include "dem_contact_hertz.h"
#include "dem_contact_law.h"
#include "dem_model.h"
#include "nc_error.h"

/* Contact kinds (the key of a contact is (sphere i, kind, j, aux); aux is 0 but for meshes and
 * net nodes). */
enum {
    DEM_CONTACT_SPHERE = 0, /* j: other sphere (j > i) */
    DEM_CONTACT_PLANE = 1,  /* j: plane index */
    DEM_CONTACT_MESH = 2,   /* j: global mesh feature id (face, edge or vertex) */
    DEM_CONTACT_NET_EDGE = 3, /* j: net edge (interior point) */
    DEM_CONTACT_NET_NODE = 4  /* j: net node (vertex), aux: the rope through it
                                 (dem_net_strands.h), one contact per rope */
};

/* A list of contacts, ordered by sphere i (then by discovery order, which is deterministic).
 * History (ft, kt_prev, fn_prev, impact_speed) survives from one step to the next through the key. The
 * contact forces themselves are summed onto spheres and walls while the list is built (see
 * dem_contact_pass.h) and not stored. */
typedef struct dem_contacts {
    size_t n, cap;
    int32_t *i, *kind, *j;
    int32_t *aux;          /* mesh index for mesh contacts, the rope for net node contacts */
    double *ft;            /* 3n: elastic tangential force on i (history) */
    double *kt_prev;       /* tangential stiffness of the previous step */
    double *fn_prev;       /* normal force of the previous step */
    double *impact_speed;  /* normal approach speed when the contact began (m/s; Hunt–Crossley) */
    double *overlap;       /* m */
    double *normal;        /* 3n: unit normal from sphere i towards the other body */
} dem_contacts;

/* The contact state of a simulation: `list` is the current list, `prev` the previous step's
 * (history); the pass swaps them at its start. */
typedef struct dem_contact_state {
    dem_contacts list, prev;
    int32_t *first, *prev_first;   /* n_spheres + 1: first record of each sphere in list / prev */
    dem_pair *wall_pairs;          /* n_materials²: sphere material a against a wall of
                                      material b (r_star, m_star filled per contact) */
} dem_contact_state;

int dem_contacts_reserve(dem_contacts *c, size_t need, nc_error *err);
void dem_contacts_free(dem_contacts *c);
/* dst = src (dst grows as needed). */
int dem_contacts_copy(dem_contacts *dst, const dem_contacts *src, nc_error *err);
/* Copies n records of src starting at `from` to dst at `to` (dst must be large enough). */
void dem_contacts_copy_range(dem_contacts *dst, size_t to, const dem_contacts *src, size_t from,
                             size_t n);

/* Allocates the index arrays and the lists for the model's spheres and tabulates the pair
 * properties (called by dem_sim_prepare once the materials are complete). */
int dem_contact_state_prepare(dem_contact_state *c, const dem_model *m, nc_error *err);
void dem_contact_state_free(dem_contact_state *c);

/* Pair properties of sphere i against a plane or mesh of the given material, from the table
 * (no divisions per contact; R* = R_i, m* = body mass: the wall does not move in response). */
static inline void dem_material_wall_pair(const dem_contact_state *c, const dem_model *m,
                                          size_t i, int material, dem_pair *p)
{
    *p = c->wall_pairs[(size_t)m->sph.material[i] * m->n_materials + (size_t)material];
    p->r_star = m->sph.radius[i];
    p->m_star = m->bod.mass[m->sph.body[i]];
}

/* Pair properties of sphere i against the net wall (its material is not in the table). */
static inline void dem_net_wall_pair(const dem_model *m, size_t i, dem_pair *p)
{
    const dem_net *net = &m->net;
    const dem_material *mi = &m->materials[m->sph.material[i]];
    p->e_star = dem_effective_modulus(mi->youngs_modulus_pa, mi->poisson_ratio,
                                      net->youngs_modulus_pa, net->poisson_ratio);
    p->g_star = dem_effective_shear(mi->shear_modulus_pa, mi->poisson_ratio,
                                    net->shear_modulus_pa, net->poisson_ratio);
    p->r_star = m->sph.radius[i];
    p->m_star = m->bod.mass[m->sph.body[i]];
    p->zeta = 0.5 * (mi->zeta + (net->zeta >= 0.0 ? net->zeta : mi->zeta));
    p->hunt_crossley = 0.5 * (mi->hunt_crossley +
                              (net->zeta >= 0.0 ? net->hunt_crossley : mi->hunt_crossley));
    p->mu = 0.5 * (mi->friction + net->friction);
    p->kt_kn_root = dem_contact_law_of(m->prm.law)->kt_kn_root(&m->prm, p->e_star, p->g_star);
}

#endif
