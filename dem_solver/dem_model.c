/* dem_model — defaults and storage of the model data (dem_model.h): growing the sphere and body
 * arrays, freeing the net and the whole model. No physics here. */
#include "dem_model.h"

#include <stdlib.h>
#include <string.h>

#include "dem_neighbor_grid.h"
#include "dem_stl.h"

void dem_model_init(dem_model *m)
{
    memset(m, 0, sizeof *m);
    m->prm.gravity[2] = -9.81;
    m->prm.dt_auto = 1;
    m->prm.dt_safety = 0.1;
    m->prm.end_time_s = 1.0;
    m->prm.output_interval_s = 0.01;
    m->prm.law = DEM_LAW_HERTZ_MINDLIN;
    m->prm.damping = DEM_DAMPING_FIT;
    m->prm.linear_kt_ratio = 2.0 / 7.0;
    m->net.restitution = -1.0;
    m->net.zeta = -1.0;
    m->net.friction = 0.3;
    m->net.poisson_ratio = 0.3;
    m->net.near_distance_m = -1.0;
}

void dem_net_free(dem_net *n)
{
    free(n->node_ids); free(n->edges); free(n->strand); free(n->ref); free(n->start); free(n->end);
    free(n->end_vel); free(n->cur); free(n->vel); free(n->force); free(n->impulse);
    free(n->box_lo); free(n->box_hi);
    if (n->grid) {
        dem_item_grid_free(n->grid);
        free(n->grid);
    }
    n->node_ids = n->edges = n->strand = NULL;
    n->ref = n->start = n->end = n->end_vel = n->cur = n->vel = n->force = n->impulse = NULL;
    n->box_lo = n->box_hi = NULL;
    n->grid = NULL;
    n->active = 0;
    n->n_nodes = n->n_edges = 0;
}

void dem_model_free(dem_model *m)
{
    free(m->materials);
    dem_spheres *p = &m->sph;
    free(p->id); free(p->body); free(p->material); free(p->radius); free(p->offset);
    free(p->pos); free(p->vel); free(p->force); free(p->torque);
    dem_bodies *b = &m->bod;
    free(b->first_sphere); free(b->n_spheres); free(b->is_cluster); free(b->mass);
    free(b->inv_mass); free(b->inv_inertia_body); free(b->inertia_body); free(b->inv_inertia_iso); free(b->pos);
    free(b->vel); free(b->omega); free(b->angmom); free(b->quat); free(b->force); free(b->torque);
    free(m->planes);
    free(m->mass_overrides);
    for (size_t k = 0; k < m->n_meshes; k++) dem_mesh_free(&m->meshes[k]);
    free(m->meshes);
    dem_net_free(&m->net);
    memset(m, 0, sizeof *m);
}

#define GROWV(ptr, per, cap)                                                                  \
    do {                                                                                      \
        void *p_ = realloc((ptr), (cap) * (per) * sizeof *(ptr));                             \
        if (!p_) return nc_error_set(err, 1, "dem: out of memory for %zu entries", (size_t)(cap)); \
        (ptr) = p_;                                                                           \
    } while (0)

int dem_model_reserve_spheres(dem_model *m, size_t need, nc_error *err)
{
    dem_spheres *p = &m->sph;
    if (need <= p->cap) return 0;
    size_t cap = p->cap ? p->cap : 64;
    while (cap < need) cap *= 2;
    GROWV(p->id, 1, cap); GROWV(p->body, 1, cap); GROWV(p->material, 1, cap);
    GROWV(p->radius, 1, cap); GROWV(p->offset, 3, cap); GROWV(p->pos, 3, cap);
    GROWV(p->vel, 3, cap); GROWV(p->force, 3, cap); GROWV(p->torque, 3, cap);
    p->cap = cap;
    return 0;
}

int dem_model_reserve_bodies(dem_model *m, size_t need, nc_error *err)
{
    dem_bodies *b = &m->bod;
    if (need <= b->cap) return 0;
    size_t cap = b->cap ? b->cap : 64;
    while (cap < need) cap *= 2;
    GROWV(b->first_sphere, 1, cap); GROWV(b->n_spheres, 1, cap); GROWV(b->is_cluster, 1, cap);
    GROWV(b->mass, 1, cap); GROWV(b->inv_mass, 1, cap); GROWV(b->inv_inertia_body, 9, cap);
    GROWV(b->inertia_body, 9, cap); GROWV(b->inv_inertia_iso, 1, cap); GROWV(b->pos, 3, cap); GROWV(b->vel, 3, cap);
    GROWV(b->omega, 3, cap); GROWV(b->angmom, 3, cap); GROWV(b->quat, 4, cap);
    GROWV(b->force, 3, cap); GROWV(b->torque, 3, cap);
    b->cap = cap;
    return 0;
}
