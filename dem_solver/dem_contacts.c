/* dem_contacts — contact detection (13)-(15), pair properties, force evaluation and the
 * deterministic reduction of contact forces onto spheres, bodies, walls and net nodes. */
#include "dem_contacts.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem_contact_geometry.h"
#include "dem_contact_hertz.h"

#define DEM_MAX_FEATURES 48 /* wall features touching one sphere in one mesh / the net */

/* ---- contact list storage ------------------------------------------------------------------- */

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
    GROW(ft, 3); GROW(kt_prev, 1); GROW(fn_prev, 1);
    GROW(overlap, 1); GROW(normal, 3);
#undef GROW
    c->cap = cap;
    return 0;
}

void dem_contacts_free(dem_contacts *c)
{
    free(c->i); free(c->kind); free(c->j); free(c->aux);
    free(c->ft); free(c->kt_prev); free(c->fn_prev);
    free(c->overlap); free(c->normal);
    memset(c, 0, sizeof *c);
}

/* Copies n records of src starting at `from` to dst at `to` (dst must be large enough). */
static void copy_range(dem_contacts *dst, size_t to, const dem_contacts *src, size_t from,
                       size_t n)
{
    if (n == 0) return;
#define CP(field, per) memcpy(dst->field + (per) * to, src->field + (per) * from, (per) * n * sizeof *src->field)
    CP(i, 1); CP(kind, 1); CP(j, 1); CP(aux, 1);
    CP(ft, 3); CP(kt_prev, 1); CP(fn_prev, 1);
    CP(overlap, 1); CP(normal, 3);
#undef CP
}

int dem_contacts_copy(dem_contacts *dst, const dem_contacts *src, nc_error *err)
{
    if (dem_contacts_reserve(dst, src->n, err)) return -1;
    copy_range(dst, 0, src, 0, src->n);
    dst->n = src->n;
    return 0;
}

/* ---- small vector helpers ------------------------------------------------------------------- */

static inline __attribute__((always_inline)) void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* ---- one contact ---------------------------------------------------------------------------- */

typedef struct contact_in {
    int kind;
    int32_t j, aux;
    double overlap;
    double n[3];           /* unit normal from sphere i towards the other body */
    double lever_i;        /* distance from i's centre to the contact point along n */
    double lever_j;        /* same for sphere j (sphere contacts) */
    double v_other[3];     /* velocity of the other body's material point at the contact */
    double weight;         /* net edge parameter t */
    double reach;          /* net: sphere radius + cable radius */
    dem_pair pair;
} contact_in;

/* Where a thread writes the contacts of the sphere it is working on, and where the forces go.
 * Forces are summed while contacts are found, in contact order (by sphere i, then discovery
 * order): directly into s->model.sph.force/torque for spheres whose contributions all come from this
 * thread's range, through the thread's spill list for walls, net nodes and spheres shared with
 * another range (those lists are summed afterwards in thread order, which is contact order).
 * So every sum runs in the same order whatever the number of threads. */
typedef struct emit_ctx {
    dem_contacts *out;
    dem_spills *spill;
    size_t first;          /* index in out of the sphere's first contact */
} emit_ctx;

static int spill_add(dem_spills *sp, int kind, int32_t index, double weight, const double f[3],
                     const double t[3])
{
    if (sp->n == sp->cap) {
        size_t cap = sp->cap ? 2 * sp->cap : 256;
        dem_spill *r = realloc(sp->r, cap * sizeof *r);
        if (!r) return -1;
        sp->r = r;
        sp->cap = cap;
    }
    dem_spill *r = &sp->r[sp->n++];
    r->kind = kind;
    r->index = index;
    r->weight = weight;
    for (int k = 0; k < 3; k++) {
        r->f[k] = f[k];
        r->t[k] = t ? t[k] : 0.0;
    }
    return 0;
}

/* Adds force f and torque t to sphere i (directly, or through the spills if it is shared). */
static inline int add_to_sphere(const dem_sim *s, emit_ctx *ctx, size_t i, const double f[3],
                                const double t[3])
{
    if (s->work.shared_sphere[i]) return spill_add(ctx->spill, DEM_CONTACT_SPHERE, (int32_t)i, 0.0, f, t);
    double *fi = s->model.sph.force + 3 * i, *ti = s->model.sph.torque + 3 * i;
    fi[0] += f[0];
    fi[1] += f[1];
    fi[2] += f[2];
    ti[0] += t[0];
    ti[1] += t[1];
    ti[2] += t[2];
    return 0;
}

/* Appends a contact record with key (i, kind, j, aux) to the thread's list and finds the history
 * of the same key from the previous step (ft, kt_prev, fn_prev; zero for a new contact). Returns
 * the record index (or -1 without memory) and in *prev the previous record (or -1). Contacts of
 * a sphere usually come in the same order as in the previous step, so the record at the same
 * position is tried first. */
static inline __attribute__((always_inline)) long new_record(const dem_sim *s, emit_ctx *ctx, size_t i, int kind, int32_t j,
                              int32_t aux, double ft[3], double *kt_prev, double *fn_prev,
                              int32_t *prev)
{
    dem_contacts *out = ctx->out;
    if (out->n == out->cap && dem_contacts_reserve(out, out->n + 1, NULL)) return -1;
    size_t c = out->n++;
    out->i[c] = (int32_t)i;
    out->kind[c] = kind;
    out->j[c] = j;
    out->aux[c] = aux;
    const dem_contacts *pv = &s->contact.prev;
    int32_t lo = s->contact.prev_first[i], hi = s->contact.prev_first[i + 1];
    int32_t hint = lo + (int32_t)(c - ctx->first);
    int32_t found = -1;
    if (hint < hi && pv->j[hint] == j && pv->kind[hint] == kind && pv->aux[hint] == aux) {
        found = hint;
    } else {
        for (int32_t p = lo; p < hi; p++)
            if (pv->kind[p] == kind && pv->j[p] == j && pv->aux[p] == aux) {
                found = p;
                break;
            }
    }
    if (found >= 0) {
        const double *h = pv->ft + 3 * (size_t)found;
        ft[0] = h[0];
        ft[1] = h[1];
        ft[2] = h[2];
        *kt_prev = pv->kt_prev[found];
        *fn_prev = pv->fn_prev[found];
    } else {
        ft[0] = ft[1] = ft[2] = 0.0;
        *kt_prev = 0.0;
        *fn_prev = 0.0;
    }
    *prev = found;
    return (long)c;
}

/* Stores the updated history and geometry of record c. */
static inline __attribute__((always_inline)) void store_record(dem_contacts *out, size_t c, const double ft[3], double kt_prev,
                                double fn_prev, double overlap, const double n[3])
{
    double *h = out->ft + 3 * c, *nn = out->normal + 3 * c;
    h[0] = ft[0];
    h[1] = ft[1];
    h[2] = ft[2];
    out->kt_prev[c] = kt_prev;
    out->fn_prev[c] = fn_prev;
    out->overlap[c] = overlap;
    nn[0] = n[0];
    nn[1] = n[1];
    nn[2] = n[2];
}

/* A contact of sphere i with a wall (plane, mesh feature, net edge or node): force, torque on
 * i and the reaction on the wall. */
static int emit(const dem_sim *s, emit_ctx *ctx, size_t i, contact_in *in, double dt)
{
    double ft[3], kt_prev, fn_prev;
    int32_t p;
    long c = new_record(s, ctx, i, in->kind, in->j, in->aux, ft, &kt_prev, &fn_prev, &p);
    if (c < 0) return -1;
    if (p >= 0 && (in->kind == DEM_CONTACT_NET_EDGE || in->kind == DEM_CONTACT_NET_NODE)) {
        /* A cable has no inside: if the normal flipped since the last step, the sphere
         * centre crossed the line (the net moved more than the overlap in one step).
         * Keep the side of the ongoing contact and count the crossing as overlap, so
         * the net pushes the sphere back instead of letting it through. */
        const double *np = s->contact.prev.normal + 3 * (size_t)p;
        if (np[0] * in->n[0] + np[1] * in->n[1] + np[2] * in->n[2] < 0.0) {
            double dist = in->reach - in->overlap;
            in->overlap = in->reach + dist;
            for (int k = 0; k < 3; k++) in->n[k] = -in->n[k];
            in->lever_i = fmax(0.0, s->model.sph.radius[i] - 0.5 * in->overlap);
        }
    }
    const double *v_i = s->model.sph.vel + 3 * i;
    const double *w_i = s->model.bod.omega + 3 * (size_t)s->model.sph.body[i];
    double r_i[3] = {in->lever_i * in->n[0], in->lever_i * in->n[1], in->lever_i * in->n[2]};
    double wr[3];
    cross3(w_i, r_i, wr);
    double vc[3]; /* (A.2) */
    for (int k = 0; k < 3; k++) vc[k] = in->v_other[k] - (v_i[k] + wr[k]);
    double f[3], t[3];
    dem_contact_force(&s->model.prm, &in->pair, in->overlap, in->n, vc, dt, ft, &kt_prev, &fn_prev, f);
    store_record(ctx->out, (size_t)c, ft, kt_prev, fn_prev, in->overlap, in->n);
    cross3(r_i, f, t);
    if (add_to_sphere(s, ctx, i, f, t)) return -1;
    /* the reaction -f on the wall, summed after the pass */
    int32_t index = in->kind == DEM_CONTACT_MESH ? in->aux : in->j;
    return spill_add(ctx->spill, in->kind, index, in->weight, f, NULL);
}

/* Pair properties of sphere i against a wall with modulus e, ν, shear g, damping zeta_w and
 * friction mu_w (R* = R_i, m* = body mass: the wall does not move in response). */
static void wall_pair(const dem_sim *s, size_t i, double e, double nu, double g, double zeta_w,
                      double mu_w, dem_pair *p)
{
    const dem_material *m = &s->model.materials[s->model.sph.material[i]];
    p->e_star = dem_effective_modulus(m->youngs_modulus_pa, m->poisson_ratio, e, nu);
    p->g_star = dem_effective_shear(m->shear_modulus_pa, m->poisson_ratio, g, nu);
    p->r_star = s->model.sph.radius[i];
    p->m_star = s->model.bod.mass[s->model.sph.body[i]];
    p->zeta = 0.5 * (m->zeta + (zeta_w >= 0.0 ? zeta_w : m->zeta));
    p->mu = 0.5 * (m->friction + mu_w);
    p->kt_kn_root = s->model.prm.law == DEM_LAW_HERTZ_MINDLIN ? sqrt(4.0 * p->g_star / p->e_star)
                                                         : sqrt(s->model.prm.linear_kt_ratio);
}

/* The same from the table made by dem_contacts_prepare (no divisions per contact). */
static void material_wall_pair(const dem_sim *s, size_t i, int material, dem_pair *p)
{
    *p = s->contact.wall_pairs[(size_t)s->model.sph.material[i] * s->model.n_materials + (size_t)material];
    p->r_star = s->model.sph.radius[i];
    p->m_star = s->model.bod.mass[s->model.sph.body[i]];
}

int dem_contacts_prepare(dem_sim *s, nc_error *err)
{
    size_t nm = s->model.n_materials;
    free(s->contact.wall_pairs);
    s->contact.wall_pairs = malloc((nm ? nm * nm : 1) * sizeof *s->contact.wall_pairs);
    if (!s->contact.wall_pairs) return nc_error_set(err, 1, "dem: out of memory for the material pairs");
    for (size_t a = 0; a < nm; a++)
        for (size_t b = 0; b < nm; b++) {
            const dem_material *m = &s->model.materials[a], *w = &s->model.materials[b];
            dem_pair *p = &s->contact.wall_pairs[a * nm + b];
            p->e_star = dem_effective_modulus(m->youngs_modulus_pa, m->poisson_ratio,
                                              w->youngs_modulus_pa, w->poisson_ratio);
            p->g_star = dem_effective_shear(m->shear_modulus_pa, m->poisson_ratio,
                                            w->shear_modulus_pa, w->poisson_ratio);
            p->r_star = p->m_star = 0.0;
            p->zeta = 0.5 * (m->zeta + (w->zeta >= 0.0 ? w->zeta : m->zeta));
            p->mu = 0.5 * (m->friction + w->friction);
            p->kt_kn_root = s->model.prm.law == DEM_LAW_HERTZ_MINDLIN ? sqrt(4.0 * p->g_star / p->e_star)
                                                                 : sqrt(s->model.prm.linear_kt_ratio);
        }
    return 0;
}

/* ---- per-sphere detection ------------------------------------------------------------------- */

/* Contacts of sphere i with its Verlet neighbours j > i (eq. (13)): the hot loop, with the
 * contact data kept in registers (no contact_in record). */
static int sphere_sphere(const dem_sim *s, emit_ctx *ctx, size_t i, double dt)
{
    const double *pi = s->model.sph.pos + 3 * i;
    double ri = s->model.sph.radius[i];
    int32_t bi = s->model.sph.body[i];
    int32_t mat_i = s->model.sph.material[i];
    const dem_material *mi = &s->model.materials[mat_i];
    double m_i = s->model.bod.mass[bi];
    const double *v_i = s->model.sph.vel + 3 * i;
    const double *w_i = s->model.bod.omega + 3 * (size_t)bi;
    int shared_i = s->work.shared_sphere[i];
    for (int32_t q = s->nlist.first[i]; q < s->nlist.first[i + 1]; q++) {
        size_t j = (size_t)s->nlist.nbr[q];
        const double *pj = s->model.sph.pos + 3 * j;
        double d[3] = {pj[0] - pi[0], pj[1] - pi[1], pj[2] - pi[2]};
        double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        double rj = s->model.sph.radius[j];
        double rs = ri + rj;
        if (d2 >= rs * rs || d2 == 0.0) continue; /* (13) */
        double dist = sqrt(d2);
        double overlap = rs - dist; /* (A.1) */
        double inv_dist = 1.0 / dist; /* one division instead of three */
        double n[3] = {d[0] * inv_dist, d[1] * inv_dist, d[2] * inv_dist};
        double lever_i = ri - 0.5 * overlap;
        double lever_j = rj - 0.5 * overlap;
        int32_t bj = s->model.sph.body[j];
        const double *vj = s->model.sph.vel + 3 * j;
        const double *wj = s->model.bod.omega + 3 * (size_t)bj;
        double rj_vec[3] = {-lever_j * n[0], -lever_j * n[1], -lever_j * n[2]};
        double wr[3];
        cross3(wj, rj_vec, wr);
        double v_other[3] = {vj[0] + wr[0], vj[1] + wr[1], vj[2] + wr[2]};
        dem_pair pair;
        int32_t mat_j = s->model.sph.material[j];
        const dem_material *mj = &s->model.materials[mat_j];
        double m_j = s->model.bod.mass[bj];
        if (mat_i == mat_j) { /* common case: no divisions */
            pair.e_star = mi->pair_e_star;
            pair.g_star = mi->pair_g_star;
            pair.kt_kn_root = mi->pair_kt_kn_root;
        } else {
            pair.e_star = dem_effective_modulus(mi->youngs_modulus_pa, mi->poisson_ratio,
                                                mj->youngs_modulus_pa, mj->poisson_ratio);
            pair.g_star = dem_effective_shear(mi->shear_modulus_pa, mi->poisson_ratio,
                                              mj->shear_modulus_pa, mj->poisson_ratio);
            pair.kt_kn_root = s->model.prm.law == DEM_LAW_HERTZ_MINDLIN
                                  ? sqrt(4.0 * pair.g_star / pair.e_star)
                                  : sqrt(s->model.prm.linear_kt_ratio);
        }
        pair.r_star = ri * rj / rs;
        pair.m_star = m_i * m_j / (m_i + m_j);
        pair.zeta = 0.5 * (mi->zeta + mj->zeta);
        pair.mu = 0.5 * (mi->friction + mj->friction);

        double ft[3], kt_prev, fn_prev;
        int32_t p;
        long c = new_record(s, ctx, i, DEM_CONTACT_SPHERE, (int32_t)j, 0, ft, &kt_prev, &fn_prev, &p);
        if (c < 0) return -1;
        double r_i[3] = {lever_i * n[0], lever_i * n[1], lever_i * n[2]};
        cross3(w_i, r_i, wr);
        double vc[3] = {v_other[0] - (v_i[0] + wr[0]), v_other[1] - (v_i[1] + wr[1]),
                        v_other[2] - (v_i[2] + wr[2])}; /* (A.2) */
        double f[3];
        dem_contact_force(&s->model.prm, &pair, overlap, n, vc, dt, ft, &kt_prev, &fn_prev, f);
        store_record(ctx->out, (size_t)c, ft, kt_prev, fn_prev, overlap, n);
        double ti[3], tj[3];
        cross3(r_i, f, ti);
        /* force -f at -r_j: torque = (-r_j) x (-f) = r_j x f */
        double r_j[3] = {lever_j * n[0], lever_j * n[1], lever_j * n[2]};
        cross3(r_j, f, tj);
        if (shared_i) {
            if (spill_add(ctx->spill, DEM_CONTACT_SPHERE, (int32_t)i, 0.0, f, ti)) return -1;
        } else {
            double *fi = s->model.sph.force + 3 * i, *tq = s->model.sph.torque + 3 * i;
            fi[0] += f[0];
            fi[1] += f[1];
            fi[2] += f[2];
            tq[0] += ti[0];
            tq[1] += ti[1];
            tq[2] += ti[2];
        }
        if (s->work.shared_sphere[j]) {
            double mf[3] = {-f[0], -f[1], -f[2]}; /* x + (-f) rounds exactly as x - f */
            if (spill_add(ctx->spill, DEM_CONTACT_SPHERE, (int32_t)j, 0.0, mf, tj)) return -1;
        } else {
            double *fj = s->model.sph.force + 3 * j, *tq = s->model.sph.torque + 3 * j;
            fj[0] -= f[0];
            fj[1] -= f[1];
            fj[2] -= f[2];
            tq[0] += tj[0];
            tq[1] += tj[1];
            tq[2] += tj[2];
        }
    }
    return 0;
}

/* Counts the neighbours j > i of sphere i within r_i + r_j + skin, other bodies only, from
 * the cell grid, and lists the first `room` of them in out (if not NULL). */
static int32_t neighbours_of(const dem_sim *s, size_t i, double skin, int32_t *out, size_t room)
{
    const double *pi = s->model.sph.pos + 3 * i;
    double ri = s->model.sph.radius[i];
    int32_t bi = s->model.sph.body[i], count = 0;
    const dem_cell_grid *g = &s->nlist.grid;
    int c[3];
    dem_cell_grid_coords(g, pi, c);
    for (int dz = -1; dz <= 1; dz++) {
        int z = c[2] + dz;
        if (z < 0 || z >= g->dims[2]) continue;
        for (int dy = -1; dy <= 1; dy++) {
            int y = c[1] + dy;
            if (y < 0 || y >= g->dims[1]) continue;
            for (int dx = -1; dx <= 1; dx++) {
                int x = c[0] + dx;
                if (x < 0 || x >= g->dims[0]) continue;
                size_t cell = ((size_t)z * (size_t)g->dims[1] + (size_t)y) * (size_t)g->dims[0] + (size_t)x;
                /* items of a cell are in increasing order: skip to those above i (one
                 * mispredicted branch per cell instead of one per item) */
                int32_t q0 = g->cell_start[cell], q1 = g->cell_start[cell + 1];
                int32_t first = q1;
                while (first > q0 && (size_t)g->cell_items[first - 1] > i) first--;
                for (int32_t q = first; q < q1; q++) {
                    int32_t j = g->cell_items[q];
                    if (s->model.sph.body[j] == bi) continue;
                    const double *pj = s->model.sph.pos + 3 * (size_t)j;
                    double d[3] = {pj[0] - pi[0], pj[1] - pi[1], pj[2] - pi[2]};
                    double cut = ri + s->model.sph.radius[j] + skin;
                    if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] >= cut * cut) continue;
                    if (out && (size_t)count < room) out[count] = j;
                    count++;
                }
            }
        }
    }
    return count;
}

/* Rebuilds the Verlet list when forced or when a sphere moved more than skin/2 since the
 * last build. Each thread lists its fixed range of spheres into its own part, the parts are
 * then joined in range order: the list does not depend on the thread count. */
static int update_neighbour_list(dem_sim *s, nc_error *err)
{
    size_t n = s->model.sph.n;
    int nb = s->work.n_buffers;
    /* s->nlist.max_disp2 was measured by dem_integrate_bodies() while moving the spheres */
    if (!(s->nlist.max_disp2 <= 0.25 * s->nlist.skin_m * s->nlist.skin_m)) s->nlist.rebuild = 1; /* also NaN */
    if (!s->nlist.rebuild) return 0;
    if (dem_cell_grid_build(&s->nlist.grid, n, s->model.sph.pos, 2.0 * s->model.r_max + s->nlist.skin_m, err)) return -1;
    int failed = 0;
#pragma omp parallel for schedule(static, 1) num_threads(nb) reduction(| : failed) if (n >= DEM_PARALLEL_MIN)
    for (int b = 0; b < nb; b++) {
        struct dem_nbr_part *part = &s->nlist.part[b];
        size_t lo = s->work.range_first[b], hi = s->work.range_first[b + 1];
        size_t used = 0;
        for (size_t i = lo; i < hi && !failed; i++) {
            size_t room = part->cap - used;
            int32_t count = neighbours_of(s, i, s->nlist.skin_m, part->a ? part->a + used : NULL, room);
            if ((size_t)count > room || part->cap - used - (size_t)count < 64) {
                size_t cap = 2 * (used + (size_t)count) + 1024;
                int32_t *a = realloc(part->a, cap * sizeof *a);
                if (!a) {
                    failed = 1;
                    break;
                }
                part->a = a;
                part->cap = cap;
                if ((size_t)count > room) neighbours_of(s, i, s->nlist.skin_m, part->a + used, (size_t)count);
            }
            s->nlist.first[i + 1] = count;
            used += (size_t)count;
        }
    }
    if (failed) return nc_error_set(err, 1, "dem: out of memory for the neighbour list");
    s->nlist.first[0] = 0;
    for (size_t i = 0; i < n; i++) s->nlist.first[i + 1] += s->nlist.first[i];
    size_t total = (size_t)s->nlist.first[n];
    if (nb == 1) { /* the single part is the list: no copy */
        int32_t *a = s->nlist.nbr;
        size_t cap = s->nlist.cap;
        s->nlist.nbr = s->nlist.part[0].a;
        s->nlist.cap = s->nlist.part[0].cap;
        s->nlist.part[0].a = a;
        s->nlist.part[0].cap = cap;
    } else {
        if (total > s->nlist.cap) {
            size_t cap = total + total / 4 + 64;
            int32_t *p = realloc(s->nlist.nbr, cap * sizeof *p);
            if (!p) return nc_error_set(err, 1, "dem: out of memory for %zu neighbour pairs", cap);
            s->nlist.nbr = p;
            s->nlist.cap = cap;
        }
#pragma omp parallel for schedule(static, 1) num_threads(nb) if (total >= DEM_PARALLEL_MIN)
        for (int b = 0; b < nb; b++) {
            size_t lo = s->work.range_first[b], hi = s->work.range_first[b + 1];
            size_t from = (size_t)s->nlist.first[lo], count = (size_t)s->nlist.first[hi] - from;
            if (count) memcpy(s->nlist.nbr + from, s->nlist.part[b].a, count * sizeof(int32_t));
        }
    }
    /* new ranges for the contact passes, balanced by the expected work of each sphere: its
     * neighbours and (weighing more) its contacts of the last step */
    if (nb > 1) {
        double work = 0.0;
        for (size_t i = 0; i < n; i++)
            work += 1.0 + (double)(s->nlist.first[i + 1] - s->nlist.first[i]) +
                    4.0 * (double)(s->contact.prev_first[i + 1] - s->contact.prev_first[i]);
        double acc = 0.0;
        int b = 1;
        s->work.range_first[0] = 0;
        for (size_t i = 0; i < n && b < nb; i++) {
            while (b < nb && acc >= work * (double)b / (double)nb) s->work.range_first[b++] = i;
            acc += 1.0 + (double)(s->nlist.first[i + 1] - s->nlist.first[i]) +
                   4.0 * (double)(s->contact.prev_first[i + 1] - s->contact.prev_first[i]);
        }
        while (b < nb) s->work.range_first[b++] = n;
        s->work.range_first[nb] = n;
    }
    /* spheres with a neighbour in another thread's range get their force sums through the
     * spills (the ranges are those of dem_compute_contacts) */
    memset(s->work.shared_sphere, 0, n * sizeof *s->work.shared_sphere);
    for (int b = 0; b + 1 < nb; b++) {
        size_t lo = s->work.range_first[b], hi = s->work.range_first[b + 1];
        for (size_t i = lo; i < hi; i++)
            for (int32_t q = s->nlist.first[i]; q < s->nlist.first[i + 1]; q++)
                if ((size_t)s->nlist.nbr[q] >= hi) s->work.shared_sphere[s->nlist.nbr[q]] = 1;
    }
    memcpy(s->nlist.pos_at_build, s->model.sph.pos, 3 * n * sizeof(double));
    s->nlist.max_disp2 = 0.0;
    s->nlist.rebuild = 0;
    s->nlist.n_builds++;
    return 0;
}

static int sphere_planes(const dem_sim *s, emit_ctx *out, size_t i, double dt)
{
    const double *p = s->model.sph.pos + 3 * i;
    double r = s->model.sph.radius[i];
    for (size_t w = 0; w < s->model.n_planes; w++) {
        const dem_plane *pl = &s->model.planes[w];
        double d = (p[0] - pl->point[0]) * pl->normal[0] + (p[1] - pl->point[1]) * pl->normal[1] +
                   (p[2] - pl->point[2]) * pl->normal[2];
        if (fabs(d) >= r) continue; /* one-sided: centres behind the plane are ignored */
        contact_in in;
        in.kind = DEM_CONTACT_PLANE;
        in.j = (int32_t)w;
        in.aux = 0;
        in.overlap = r - d;
        for (int k = 0; k < 3; k++) in.n[k] = -pl->normal[k];
        in.lever_i = r - 0.5 * in.overlap;
        in.lever_j = 0.0;
        memcpy(in.v_other, pl->velocity, sizeof in.v_other);
        in.weight = 0.0;
        material_wall_pair(s, i, pl->material, &in.pair);
        if (emit(s, out, i, &in, dt)) return -1;
    }
    return 0;
}

typedef struct feature {
    int type;      /* 0 face, 1 edge, 2 vertex (mesh); 1 edge, 2 node (net) */
    int32_t id;    /* triangle / edge / vertex index */
    int32_t owner; /* triangle (mesh) or edge (net) that produced it */
    double q[3];   /* closest point */
    double d2;
    double t;      /* net edge parameter */
} feature;

static int add_feature(feature *f, int *n, const feature *x, int *overflow)
{
    for (int k = 0; k < *n; k++)
        if (f[k].type == x->type && f[k].id == x->id) return 0; /* shared feature: once */
    if (*n == DEM_MAX_FEATURES) {
        *overflow = 1;
        return 0;
    }
    f[(*n)++] = *x;
    return 0;
}

static int sphere_meshes(const dem_sim *s, emit_ctx *out, size_t i, double dt, int *overflow)
{
    const double *pw = s->model.sph.pos + 3 * i;
    double r = s->model.sph.radius[i];
    feature f[DEM_MAX_FEATURES];
    for (size_t m = 0; m < s->model.n_meshes; m++) {
        const dem_mesh *mesh = &s->model.meshes[m];
        double p[3] = {pw[0] - mesh->offset[0], pw[1] - mesh->offset[1], pw[2] - mesh->offset[2]};
        const int32_t *items;
        size_t count = dem_item_grid_query(mesh->grid, p, &items);
        int nf = 0;
        for (size_t c = 0; c < count; c++) {
            int32_t t = items[c];
            const int32_t *v = mesh->tri + 3 * (size_t)t;
            feature x;
            dem_tri_feature which;
            x.d2 = dem_closest_on_triangle(p, mesh->vertices + 3 * (size_t)v[0],
                                           mesh->vertices + 3 * (size_t)v[1],
                                           mesh->vertices + 3 * (size_t)v[2], x.q, &which);
            if (x.d2 >= r * r || x.d2 == 0.0) continue; /* (15) for rigid triangles */
            x.owner = t;
            x.t = 0.0;
            if (which == DEM_TRI_FACE) {
                x.type = 0;
                x.id = t;
            } else if (which <= DEM_TRI_EDGE2) {
                x.type = 1;
                x.id = mesh->tri_edges[3 * (size_t)t + (size_t)(which - DEM_TRI_EDGE0)];
            } else {
                x.type = 2;
                x.id = v[which - DEM_TRI_VERT0];
            }
            add_feature(f, &nf, &x, overflow);
        }
        for (int a = 0; a < nf; a++) {
            /* An edge next to a touched face, or a vertex of a touched face or edge, lies on
             * the same surface as that contact: counting it again would double the force. */
            int drop = 0;
            for (int b = 0; b < nf && !drop; b++) {
                if (b == a) continue;
                if (f[b].type == 0 && f[a].type == 1) {
                    const int32_t *e = mesh->tri_edges + 3 * (size_t)f[b].id;
                    drop = e[0] == f[a].id || e[1] == f[a].id || e[2] == f[a].id;
                } else if (f[b].type == 0 && f[a].type == 2) {
                    const int32_t *v = mesh->tri + 3 * (size_t)f[b].id;
                    drop = v[0] == f[a].id || v[1] == f[a].id || v[2] == f[a].id;
                } else if (f[b].type == 1 && f[a].type == 2) {
                    const int32_t *e = mesh->edges + 2 * (size_t)f[b].id;
                    drop = e[0] == f[a].id || e[1] == f[a].id;
                }
            }
            if (drop) continue;
            double dist = sqrt(f[a].d2);
            contact_in in;
            in.kind = DEM_CONTACT_MESH;
            in.aux = (int32_t)m;
            in.j = f[a].type == 0 ? f[a].id
                   : f[a].type == 1 ? (int32_t)mesh->n_triangles + f[a].id
                                    : (int32_t)(mesh->n_triangles + mesh->n_edges) + f[a].id;
            in.overlap = r - dist;
            for (int k = 0; k < 3; k++) in.n[k] = (f[a].q[k] - p[k]) / dist;
            in.lever_i = r - 0.5 * in.overlap;
            in.lever_j = 0.0;
            memcpy(in.v_other, mesh->velocity, sizeof in.v_other);
            in.weight = 0.0;
            material_wall_pair(s, i, mesh->material, &in.pair);
            if (emit(s, out, i, &in, dt)) return -1;
        }
    }
    return 0;
}

static int sphere_net(const dem_sim *s, emit_ctx *out, size_t i, double dt, int *overflow)
{
    const dem_net *net = &s->model.net;
    const double *p = s->model.sph.pos + 3 * i;
    double reach = s->model.sph.radius[i] + net->cable_radius_m;
    const int32_t *items;
    size_t count = dem_item_grid_query(net->grid, p, &items);
    feature f[DEM_MAX_FEATURES];
    int nf = 0;
    for (size_t c = 0; c < count; c++) {
        int32_t e = items[c];
        int32_t a = net->edges[2 * (size_t)e], b = net->edges[2 * (size_t)e + 1];
        feature x;
        x.d2 = dem_closest_on_segment(p, net->cur + 3 * (size_t)a, net->cur + 3 * (size_t)b, x.q, &x.t);
        if (x.d2 >= reach * reach || x.d2 == 0.0) continue; /* (14), (15) */
        x.owner = e;
        if (x.t <= 0.0) {
            x.type = 2;
            x.id = a;
        } else if (x.t >= 1.0) {
            x.type = 2;
            x.id = b;
        } else {
            x.type = 1;
            x.id = e;
        }
        add_feature(f, &nf, &x, overflow);
    }
    for (int a = 0; a < nf; a++) {
        if (f[a].type == 2) { /* a node of an edge touched in its interior is the same contact */
            int drop = 0;
            for (int b = 0; b < nf && !drop; b++) {
                if (f[b].type != 1) continue;
                const int32_t *e = net->edges + 2 * (size_t)f[b].id;
                drop = e[0] == f[a].id || e[1] == f[a].id;
            }
            if (drop) continue;
        }
        double dist = sqrt(f[a].d2);
        contact_in in;
        in.aux = 0;
        in.reach = reach;
        in.overlap = reach - dist;
        for (int k = 0; k < 3; k++) in.n[k] = (f[a].q[k] - p[k]) / dist;
        in.lever_i = s->model.sph.radius[i] - 0.5 * in.overlap;
        in.lever_j = 0.0;
        if (f[a].type == 1) {
            in.kind = DEM_CONTACT_NET_EDGE;
            in.j = f[a].id;
            in.weight = f[a].t;
            const int32_t *e = net->edges + 2 * (size_t)f[a].id;
            const double *va = net->vel + 3 * (size_t)e[0], *vb = net->vel + 3 * (size_t)e[1];
            for (int k = 0; k < 3; k++) in.v_other[k] = (1.0 - in.weight) * va[k] + in.weight * vb[k];
        } else {
            in.kind = DEM_CONTACT_NET_NODE;
            in.j = f[a].id;
            in.weight = 0.0;
            memcpy(in.v_other, net->vel + 3 * (size_t)f[a].id, sizeof in.v_other);
        }
        wall_pair(s, i, net->youngs_modulus_pa, net->poisson_ratio, net->shear_modulus_pa,
                  net->zeta, net->friction, &in.pair);
        if (emit(s, out, i, &in, dt)) return -1;
    }
    return 0;
}

int dem_contacts_close_pairs(dem_sim *s, double gap, long *count, nc_error *err)
{
    size_t n = s->model.sph.n;
    *count = 0;
    if (n < 2) return 0;
    if (dem_cell_grid_build(&s->nlist.grid, n, s->model.sph.pos, 2.0 * s->model.r_max + gap, err)) return -1;
    long nl = (long)n, total = 0;
#pragma omp parallel for schedule(static) reduction(+ : total) num_threads(s->work.n_buffers) if (nl >= DEM_PARALLEL_MIN)
    for (long i = 0; i < nl; i++) total += neighbours_of(s, (size_t)i, gap, NULL, 0);
    *count = total;
    s->nlist.rebuild = 1; /* the grid now has another cell size */
    return 0;
}

/* ---- the step's contact pass ---------------------------------------------------------------- */

int dem_compute_contacts(dem_sim *s, double dt, nc_error *err)
{
    size_t n = s->model.sph.n;
    /* the current list becomes the history */
    dem_contacts tmp = s->contact.prev;
    s->contact.prev = s->contact.list;
    s->contact.list = tmp;
    int32_t *tf = s->contact.prev_first;
    s->contact.prev_first = s->contact.first;
    s->contact.first = tf;

    if (update_neighbour_list(s, err)) return -1;

    int nb = s->work.n_buffers;
    int failed = 0;
    /* Fixed contiguous ranges per buffer: the concatenation order never changes. */
#pragma omp parallel for schedule(static, 1) num_threads(nb) reduction(| : failed) if (n >= DEM_PARALLEL_MIN)
    for (int b = 0; b < nb; b++) {
        emit_ctx out = {&s->work.buffers[b], &s->work.spills[b], 0};
        out.out->n = 0;
        out.spill->n = 0;
        s->work.overflow[b] = 0;
        size_t lo = s->work.range_first[b], hi = s->work.range_first[b + 1];
        /* only this range writes the sums of its unshared spheres */
        memset(s->model.sph.force + 3 * lo, 0, 3 * (hi - lo) * sizeof(double));
        memset(s->model.sph.torque + 3 * lo, 0, 3 * (hi - lo) * sizeof(double));
        for (size_t i = lo; i < hi && !failed; i++) {
            out.first = out.out->n;
            s->contact.first[i] = (int32_t)out.first; /* + the buffer's offset, below */
            if (sphere_sphere(s, &out, i, dt) || sphere_planes(s, &out, i, dt) ||
                (s->model.n_meshes && sphere_meshes(s, &out, i, dt, &s->work.overflow[b])) ||
                (s->model.net.active && sphere_net(s, &out, i, dt, &s->work.overflow[b])))
                failed = 1;
        }
    }
    if (failed) return nc_error_set(err, 1, "dem: out of memory growing the contact list");
    size_t total = 0;
    for (int b = 0; b < nb; b++) {
        if (s->work.overflow[b])
            return nc_error_set(err, 1, "dem: a sphere touches more than %d features of one wall "
                                        "mesh or of the net (mesh much finer than the spheres?)",
                                DEM_MAX_FEATURES);
        total += s->work.buffers[b].n;
    }
    if (nb == 1) { /* the single buffer becomes the list: no copy */
        dem_contacts t = s->contact.list;
        s->contact.list = s->work.buffers[0];
        s->work.buffers[0] = t;
    } else {
        if (dem_contacts_reserve(&s->contact.list, total, err)) return -1;
        size_t at[DEM_MAX_BUFFERS + 1];
        at[0] = 0;
        for (int b = 0; b < nb; b++) at[b + 1] = at[b] + s->work.buffers[b].n;
#pragma omp parallel for schedule(static, 1) num_threads(nb) if (total >= DEM_PARALLEL_MIN)
        for (int b = 0; b < nb; b++) copy_range(&s->contact.list, at[b], &s->work.buffers[b], 0, s->work.buffers[b].n);
        s->contact.list.n = total;
    }

    /* CSR index by sphere: each buffer's local first contacts, shifted by its offset */
    if (nb > 1) {
        size_t off = 0;
        for (int b = 0; b < nb; b++) {
            size_t lo = s->work.range_first[b], hi = s->work.range_first[b + 1];
            for (size_t i = lo; i < hi; i++) s->contact.first[i] += (int32_t)off;
            off += s->work.buffers[b].n;
        }
    }
    s->contact.first[n] = (int32_t)total;

    /* the sums that cross ranges, in contact order (thread ranges are in sphere order) */
    memset(s->wall_force, 0, 3 * s->n_walls * sizeof(double));
    if (s->model.net.active) memset(s->model.net.force, 0, 3 * s->model.net.n_nodes * sizeof(double));
    double *net_total = s->wall_force + 3 * (s->model.n_planes + s->model.n_meshes);
    for (int b = 0; b < nb; b++) {
        const dem_spills *sp = &s->work.spills[b];
        for (size_t k = 0; k < sp->n; k++) {
            const dem_spill *r = &sp->r[k];
            const double *f = r->f;
            switch (r->kind) {
            case DEM_CONTACT_SPHERE: {
                double *fs = s->model.sph.force + 3 * (size_t)r->index, *ts = s->model.sph.torque + 3 * (size_t)r->index;
                for (int d = 0; d < 3; d++) {
                    fs[d] += f[d];
                    ts[d] += r->t[d];
                }
                break;
            }
            case DEM_CONTACT_PLANE:
                for (int d = 0; d < 3; d++) s->wall_force[3 * (size_t)r->index + d] -= f[d];
                break;
            case DEM_CONTACT_MESH:
                for (int d = 0; d < 3; d++) s->wall_force[3 * (s->model.n_planes + (size_t)r->index) + d] -= f[d];
                break;
            case DEM_CONTACT_NET_EDGE: { /* consistent nodal loads: (1-t) f, t f */
                const int32_t *e = s->model.net.edges + 2 * (size_t)r->index;
                double t = r->weight;
                for (int d = 0; d < 3; d++) {
                    s->model.net.force[3 * (size_t)e[0] + d] -= (1.0 - t) * f[d];
                    s->model.net.force[3 * (size_t)e[1] + d] -= t * f[d];
                    net_total[d] -= f[d];
                }
                break;
            }
            case DEM_CONTACT_NET_NODE:
                for (int d = 0; d < 3; d++) {
                    s->model.net.force[3 * (size_t)r->index + d] -= f[d];
                    net_total[d] -= f[d];
                }
                break;
            default:
                break;
            }
        }
    }

    return 0;
}

double dem_contacts_elastic_energy(const dem_sim *s)
{
    const dem_contacts *c = &s->contact.list;
    double e = 0.0;
    for (size_t k = 0; k < c->n; k++) {
        size_t i = (size_t)c->i[k];
        dem_pair p;
        switch (c->kind[k]) {
        case DEM_CONTACT_SPHERE: {
            size_t j = (size_t)c->j[k];
            const dem_material *mi = &s->model.materials[s->model.sph.material[i]];
            const dem_material *mj = &s->model.materials[s->model.sph.material[j]];
            p.e_star = dem_effective_modulus(mi->youngs_modulus_pa, mi->poisson_ratio,
                                             mj->youngs_modulus_pa, mj->poisson_ratio);
            p.r_star = s->model.sph.radius[i] * s->model.sph.radius[j] / (s->model.sph.radius[i] + s->model.sph.radius[j]);
            break;
        }
        case DEM_CONTACT_PLANE:
            material_wall_pair(s, i, s->model.planes[c->j[k]].material, &p);
            break;
        case DEM_CONTACT_MESH:
            material_wall_pair(s, i, s->model.meshes[c->aux[k]].material, &p);
            break;
        default:
            wall_pair(s, i, s->model.net.youngs_modulus_pa, s->model.net.poisson_ratio,
                      s->model.net.shear_modulus_pa, s->model.net.zeta, s->model.net.friction, &p);
            break;
        }
        double d = c->overlap[k];
        if (s->model.prm.law == DEM_LAW_HERTZ_MINDLIN)
            e += 8.0 / 15.0 * p.e_star * sqrt(p.r_star) * pow(d, 2.5); /* ∫ 4/3 E* sqrt(R*) δ^1.5 dδ */
        else
            e += 0.5 * s->model.prm.linear_kn_n_per_m * d * d;
        const double *ft = c->ft + 3 * k;
        if (c->kt_prev[k] > 0.0) e += 0.5 * (ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2]) / c->kt_prev[k];
    }
    return e;
}
