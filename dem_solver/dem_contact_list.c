/* dem_contact_list — storage of contact lists (reserve, copy, free), the contact state's
 * allocation and the table of sphere-material against wall-material pair properties. */
#include "dem_contact_list.h"

#include <stdlib.h>
#include <string.h>

int dem_contacts_reserve(dem_contacts *c, size_t need, nc_error *err)
{
    if (need <= c->cap) return 0;
    size_t cap = c->cap ? c->cap : 256;
    while (cap < need) cap *= 2;
#define GROW(field, per)                                                                      \
    do {                                                                                      \
        void *p_ = realloc(c->field, cap * (per) * sizeof *c->field);                         \
        if (!p_) return nc_error_set(err, 1, "dem: out of memory for %zu contacts", cap);     \
        c->field = p_;                                                                        \
    } while (0)
    GROW(i, 1); GROW(kind, 1); GROW(j, 1); GROW(aux, 1);
    GROW(ft, 3); GROW(kt_prev, 1); GROW(fn_prev, 1); GROW(impact_speed, 1);
    GROW(overlap, 1); GROW(normal, 3);
#undef GROW
    c->cap = cap;
    return 0;
}

void dem_contacts_free(dem_contacts *c)
{
    free(c->i); free(c->kind); free(c->j); free(c->aux);
    free(c->ft); free(c->kt_prev); free(c->fn_prev); free(c->impact_speed);
    free(c->overlap); free(c->normal);
    memset(c, 0, sizeof *c);
}

void dem_contacts_copy_range(dem_contacts *dst, size_t to, const dem_contacts *src, size_t from,
                             size_t n)
{
    if (n == 0) return;
#define CP(field, per) memcpy(dst->field + (per) * to, src->field + (per) * from, (per) * n * sizeof *src->field)
    CP(i, 1); CP(kind, 1); CP(j, 1); CP(aux, 1);
    CP(ft, 3); CP(kt_prev, 1); CP(fn_prev, 1); CP(impact_speed, 1);
    CP(overlap, 1); CP(normal, 3);
#undef CP
}

int dem_contacts_copy(dem_contacts *dst, const dem_contacts *src, nc_error *err)
{
    if (dem_contacts_reserve(dst, src->n, err)) return -1;
    dem_contacts_copy_range(dst, 0, src, 0, src->n);
    dst->n = src->n;
    return 0;
}

/* E*, G*, ζ, μ and sqrt(kt/kn') of every (sphere material, wall material) pair. */
static int build_wall_pairs(dem_contact_state *c, const dem_model *md, nc_error *err)
{
    size_t nm = md->n_materials;
    free(c->wall_pairs);
    c->wall_pairs = malloc((nm ? nm * nm : 1) * sizeof *c->wall_pairs);
    if (!c->wall_pairs) return nc_error_set(err, 1, "dem: out of memory for the material pairs");
    for (size_t a = 0; a < nm; a++)
        for (size_t b = 0; b < nm; b++) {
            const dem_material *m = &md->materials[a], *w = &md->materials[b];
            dem_pair *p = &c->wall_pairs[a * nm + b];
            p->e_star = dem_effective_modulus(m->youngs_modulus_pa, m->poisson_ratio,
                                              w->youngs_modulus_pa, w->poisson_ratio);
            p->g_star = dem_effective_shear(m->shear_modulus_pa, m->poisson_ratio,
                                            w->shear_modulus_pa, w->poisson_ratio);
            p->r_star = p->m_star = 0.0;
            p->zeta = 0.5 * (m->zeta + (w->zeta >= 0.0 ? w->zeta : m->zeta));
            p->hunt_crossley = 0.5 * (m->hunt_crossley + (w->zeta >= 0.0 ? w->hunt_crossley : m->hunt_crossley));
            p->mu = 0.5 * (m->friction + w->friction);
            p->kt_kn_root = dem_contact_law_of(md->prm.law)->kt_kn_root(&md->prm, p->e_star, p->g_star);
        }
    return 0;
}

int dem_contact_state_prepare(dem_contact_state *c, const dem_model *m, nc_error *err)
{
    size_t n = m->sph.n;
    c->first = calloc(n + 1, sizeof *c->first);
    c->prev_first = calloc(n + 1, sizeof *c->prev_first);
    if (!c->first || !c->prev_first)
        return nc_error_set(err, 1, "dem: out of memory for %zu spheres", n);
    if (dem_contacts_reserve(&c->list, 8 * n + 64, err) ||
        dem_contacts_reserve(&c->prev, 8 * n + 64, err))
        return -1;
    return build_wall_pairs(c, m, err);
}

void dem_contact_state_free(dem_contact_state *c)
{
    dem_contacts_free(&c->list);
    dem_contacts_free(&c->prev);
    free(c->first);
    free(c->prev_first);
    free(c->wall_pairs);
    memset(c, 0, sizeof *c);
}
