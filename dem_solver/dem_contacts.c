/* dem_contacts — contact detection (13)-(15), pair properties, force evaluation and the
 * deterministic reduction of contact forces onto spheres, bodies, walls and net nodes. */
#include "dem_contacts.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

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
    GROW(force, 3); GROW(torque_i, 3); GROW(torque_j, 3);
    GROW(weight, 1); GROW(overlap, 1); GROW(normal, 3);
#undef GROW
    c->cap = cap;
    return 0;
}

void dem_contacts_free(dem_contacts *c)
{
    free(c->i); free(c->kind); free(c->j); free(c->aux);
    free(c->ft); free(c->kt_prev); free(c->fn_prev);
    free(c->force); free(c->torque_i); free(c->torque_j);
    free(c->weight); free(c->overlap); free(c->normal);
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
    CP(force, 3); CP(torque_i, 3); CP(torque_j, 3);
    CP(weight, 1); CP(overlap, 1); CP(normal, 3);
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

static inline void cross3(const double a[3], const double b[3], double out[3])
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

/* Where a thread writes the contacts of the sphere it is working on. */
typedef struct emit_ctx {
    dem_contacts *out;
    size_t first;          /* index in out of the sphere's first contact */
} emit_ctx;

/* Appends the contact to the thread's list, with the history of the same key from the previous
 * step. Contacts of a sphere usually come in the same order as in the previous step, so the
 * record at the same position is tried first. */
static int emit(const dem_sim *s, emit_ctx *ctx, size_t i, contact_in *in, double dt)
{
    dem_contacts *out = ctx->out;
    if (out->n == out->cap && dem_contacts_reserve(out, out->n + 1, NULL)) return -1;
    size_t c = out->n++;
    out->i[c] = (int32_t)i;
    out->kind[c] = in->kind;
    out->j[c] = in->j;
    out->aux[c] = in->aux;
    double *ft = out->ft + 3 * c;
    ft[0] = ft[1] = ft[2] = 0.0;
    out->kt_prev[c] = 0.0;
    out->fn_prev[c] = 0.0;
    int32_t lo = s->prev_first[i], hi = s->prev_first[i + 1];
    int32_t hint = lo + (int32_t)(c - ctx->first);
    if (hint < hi && s->prev.j[hint] == in->j && s->prev.kind[hint] == in->kind &&
        s->prev.aux[hint] == in->aux) {
        lo = hint;
        hi = hint + 1;
    }
    for (int32_t p = lo; p < hi; p++) {
        if (s->prev.kind[p] == in->kind && s->prev.j[p] == in->j && s->prev.aux[p] == in->aux) {
            memcpy(ft, s->prev.ft + 3 * (size_t)p, 3 * sizeof *ft);
            out->kt_prev[c] = s->prev.kt_prev[p];
            out->fn_prev[c] = s->prev.fn_prev[p];
            if (in->kind == DEM_CONTACT_NET_EDGE || in->kind == DEM_CONTACT_NET_NODE) {
                /* A cable has no inside: if the normal flipped since the last step, the sphere
                 * centre crossed the line (the net moved more than the overlap in one step).
                 * Keep the side of the ongoing contact and count the crossing as overlap, so
                 * the net pushes the sphere back instead of letting it through. */
                const double *np = s->prev.normal + 3 * (size_t)p;
                if (np[0] * in->n[0] + np[1] * in->n[1] + np[2] * in->n[2] < 0.0) {
                    double dist = in->reach - in->overlap;
                    in->overlap = in->reach + dist;
                    for (int k = 0; k < 3; k++) in->n[k] = -in->n[k];
                    in->lever_i = fmax(0.0, s->sph.radius[i] - 0.5 * in->overlap);
                }
            }
            break;
        }
    }
    const double *v_i = s->sph.vel + 3 * i;
    const double *w_i = s->bod.omega + 3 * (size_t)s->sph.body[i];
    double r_i[3] = {in->lever_i * in->n[0], in->lever_i * in->n[1], in->lever_i * in->n[2]};
    double wr[3];
    cross3(w_i, r_i, wr);
    double vc[3]; /* (A.2) */
    for (int k = 0; k < 3; k++) vc[k] = in->v_other[k] - (v_i[k] + wr[k]);
    double *f = out->force + 3 * c;
    dem_contact_force(&s->prm, &in->pair, in->overlap, in->n, vc, dt, ft, &out->kt_prev[c],
                      &out->fn_prev[c], f);
    cross3(r_i, f, out->torque_i + 3 * c);
    if (in->kind == DEM_CONTACT_SPHERE) {
        double r_j[3] = {in->lever_j * in->n[0], in->lever_j * in->n[1], in->lever_j * in->n[2]};
        /* force -f at -r_j: torque = (-r_j) x (-f) = r_j x f */
        cross3(r_j, f, out->torque_j + 3 * c);
    } else {
        double *tj = out->torque_j + 3 * c;
        tj[0] = tj[1] = tj[2] = 0.0;
    }
    out->weight[c] = in->weight;
    out->overlap[c] = in->overlap;
    memcpy(out->normal + 3 * c, in->n, 3 * sizeof(double));
    return 0;
}

/* Pair properties of sphere i against a wall with modulus e, ν, shear g, damping zeta_w and
 * friction mu_w (R* = R_i, m* = body mass: the wall does not move in response). */
static void wall_pair(const dem_sim *s, size_t i, double e, double nu, double g, double zeta_w,
                      double mu_w, dem_pair *p)
{
    const dem_material *m = &s->materials[s->sph.material[i]];
    p->e_star = dem_effective_modulus(m->youngs_modulus_pa, m->poisson_ratio, e, nu);
    p->g_star = dem_effective_shear(m->shear_modulus_pa, m->poisson_ratio, g, nu);
    p->r_star = s->sph.radius[i];
    p->m_star = s->bod.mass[s->sph.body[i]];
    p->zeta = 0.5 * (m->zeta + (zeta_w >= 0.0 ? zeta_w : m->zeta));
    p->mu = 0.5 * (m->friction + mu_w);
    p->kt_kn_root = s->prm.law == DEM_LAW_HERTZ_MINDLIN ? sqrt(4.0 * p->g_star / p->e_star)
                                                         : sqrt(s->prm.linear_kt_ratio);
}

static void material_wall_pair(const dem_sim *s, size_t i, int material, dem_pair *p)
{
    const dem_material *w = &s->materials[material];
    wall_pair(s, i, w->youngs_modulus_pa, w->poisson_ratio, w->shear_modulus_pa, w->zeta,
              w->friction, p);
}

/* ---- per-sphere detection ------------------------------------------------------------------- */

/* Contacts of sphere i with its Verlet neighbours j > i (eq. (13)). */
static int sphere_sphere(const dem_sim *s, emit_ctx *out, size_t i, double dt)
{
    const double *pi = s->sph.pos + 3 * i;
    double ri = s->sph.radius[i];
    int32_t bi = s->sph.body[i];
    for (int32_t q = s->nbr_first[i]; q < s->nbr_first[i + 1]; q++) {
        size_t j = (size_t)s->nbr[q];
        const double *pj = s->sph.pos + 3 * j;
        double d[3] = {pj[0] - pi[0], pj[1] - pi[1], pj[2] - pi[2]};
        double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        double rj = s->sph.radius[j];
        double rs = ri + rj;
        if (d2 >= rs * rs || d2 == 0.0) continue; /* (13) */
        double dist = sqrt(d2);
        contact_in in;
        in.kind = DEM_CONTACT_SPHERE;
        in.j = (int32_t)j;
        in.aux = 0;
        in.overlap = rs - dist; /* (A.1) */
        for (int k = 0; k < 3; k++) in.n[k] = d[k] / dist;
        in.lever_i = ri - 0.5 * in.overlap;
        in.lever_j = rj - 0.5 * in.overlap;
        const double *vj = s->sph.vel + 3 * j;
        const double *wj = s->bod.omega + 3 * (size_t)s->sph.body[j];
        double rj_vec[3] = {-in.lever_j * in.n[0], -in.lever_j * in.n[1], -in.lever_j * in.n[2]};
        double wr[3];
        cross3(wj, rj_vec, wr);
        for (int k = 0; k < 3; k++) in.v_other[k] = vj[k] + wr[k];
        in.weight = 0.0;
        const dem_material *mi = &s->materials[s->sph.material[i]];
        const dem_material *mj = &s->materials[s->sph.material[j]];
        double m_i = s->bod.mass[bi], m_j = s->bod.mass[s->sph.body[j]];
        if (s->sph.material[i] == s->sph.material[j]) { /* common case: no divisions */
            in.pair.e_star = mi->pair_e_star;
            in.pair.g_star = mi->pair_g_star;
            in.pair.kt_kn_root = mi->pair_kt_kn_root;
        } else {
            in.pair.e_star = dem_effective_modulus(mi->youngs_modulus_pa, mi->poisson_ratio,
                                                   mj->youngs_modulus_pa, mj->poisson_ratio);
            in.pair.g_star = dem_effective_shear(mi->shear_modulus_pa, mi->poisson_ratio,
                                                 mj->shear_modulus_pa, mj->poisson_ratio);
            in.pair.kt_kn_root = s->prm.law == DEM_LAW_HERTZ_MINDLIN
                                     ? sqrt(4.0 * in.pair.g_star / in.pair.e_star)
                                     : sqrt(s->prm.linear_kt_ratio);
        }
        in.pair.r_star = ri * rj / rs;
        in.pair.m_star = m_i * m_j / (m_i + m_j);
        in.pair.zeta = 0.5 * (mi->zeta + mj->zeta);
        in.pair.mu = 0.5 * (mi->friction + mj->friction);
        if (emit(s, out, i, &in, dt)) return -1;
    }
    return 0;
}

/* Counts (out == NULL) or lists the neighbours j > i of sphere i within r_i + r_j + skin,
 * other bodies only, from the cell grid. */
static int32_t neighbours_of(const dem_sim *s, size_t i, double skin, int32_t *out)
{
    const double *pi = s->sph.pos + 3 * i;
    double ri = s->sph.radius[i];
    int32_t bi = s->sph.body[i], count = 0;
    const dem_cell_grid *g = &s->grid;
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
                for (int32_t q = g->cell_start[cell]; q < g->cell_start[cell + 1]; q++) {
                    int32_t j = g->cell_items[q];
                    if ((size_t)j <= i || s->sph.body[j] == bi) continue;
                    const double *pj = s->sph.pos + 3 * (size_t)j;
                    double d[3] = {pj[0] - pi[0], pj[1] - pi[1], pj[2] - pi[2]};
                    double cut = ri + s->sph.radius[j] + skin;
                    if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] >= cut * cut) continue;
                    if (out) out[count] = j;
                    count++;
                }
            }
        }
    }
    return count;
}

/* Rebuilds the Verlet list when forced or when a sphere moved more than skin/2 since the
 * last build. Two passes (count, fill) keep the list independent of the thread count. */
static int update_neighbour_list(dem_sim *s, nc_error *err)
{
    size_t n = s->sph.n;
    int nb = s->n_buffers;
    /* s->max_disp2 was measured by dem_integrate_bodies() while moving the spheres */
    if (!(s->max_disp2 <= 0.25 * s->skin_m * s->skin_m)) s->rebuild = 1; /* also NaN */
    if (!s->rebuild) return 0;
    if (dem_cell_grid_build(&s->grid, n, s->sph.pos, 2.0 * s->r_max + s->skin_m, err)) return -1;
    long nl = (long)n;
#pragma omp parallel for schedule(static) num_threads(nb) if (nl >= DEM_PARALLEL_MIN)
    for (long i = 0; i < nl; i++) s->nbr_first[i + 1] = neighbours_of(s, (size_t)i, s->skin_m, NULL);
    s->nbr_first[0] = 0;
    for (size_t i = 0; i < n; i++) s->nbr_first[i + 1] += s->nbr_first[i];
    size_t total = (size_t)s->nbr_first[n];
    if (total > s->nbr_cap) {
        size_t cap = total + total / 4 + 64;
        int32_t *p = realloc(s->nbr, cap * sizeof *p);
        if (!p) return nc_error_set(err, 1, "dem: out of memory for %zu neighbour pairs", cap);
        s->nbr = p;
        s->nbr_cap = cap;
    }
#pragma omp parallel for schedule(static) num_threads(nb) if (nl >= DEM_PARALLEL_MIN)
    for (long i = 0; i < nl; i++) neighbours_of(s, (size_t)i, s->skin_m, s->nbr + s->nbr_first[i]);
    memcpy(s->pos_at_build, s->sph.pos, 3 * n * sizeof(double));
    s->max_disp2 = 0.0;
    s->rebuild = 0;
    s->n_builds++;
    return 0;
}

static int sphere_planes(const dem_sim *s, emit_ctx *out, size_t i, double dt)
{
    const double *p = s->sph.pos + 3 * i;
    double r = s->sph.radius[i];
    for (size_t w = 0; w < s->n_planes; w++) {
        const dem_plane *pl = &s->planes[w];
        double d = (p[0] - pl->point[0]) * pl->normal[0] + (p[1] - pl->point[1]) * pl->normal[1] +
                   (p[2] - pl->point[2]) * pl->normal[2];
        if (d >= r || d <= -r) continue; /* one-sided: centres behind the plane are ignored */
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
    const double *pw = s->sph.pos + 3 * i;
    double r = s->sph.radius[i];
    feature f[DEM_MAX_FEATURES];
    for (size_t m = 0; m < s->n_meshes; m++) {
        const dem_mesh *mesh = &s->meshes[m];
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
    const dem_net *net = &s->net;
    const double *p = s->sph.pos + 3 * i;
    double reach = s->sph.radius[i] + net->cable_radius_m;
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
        in.lever_i = s->sph.radius[i] - 0.5 * in.overlap;
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
    size_t n = s->sph.n;
    *count = 0;
    if (n < 2) return 0;
    if (dem_cell_grid_build(&s->grid, n, s->sph.pos, 2.0 * s->r_max + gap, err)) return -1;
    long nl = (long)n, total = 0;
#pragma omp parallel for schedule(static) reduction(+ : total) num_threads(s->n_buffers) if (nl >= DEM_PARALLEL_MIN)
    for (long i = 0; i < nl; i++) total += neighbours_of(s, (size_t)i, gap, NULL);
    *count = total;
    s->rebuild = 1; /* the grid now has another cell size */
    return 0;
}

/* ---- the step's contact pass ---------------------------------------------------------------- */

int dem_compute_contacts(dem_sim *s, double dt, nc_error *err)
{
    size_t n = s->sph.n;
    /* the current list becomes the history */
    dem_contacts tmp = s->prev;
    s->prev = s->contacts;
    s->contacts = tmp;
    int32_t *tf = s->prev_first;
    s->prev_first = s->contact_first;
    s->contact_first = tf;

    if (update_neighbour_list(s, err)) return -1;

    int nb = s->n_buffers;
    int failed = 0;
#pragma omp parallel num_threads(nb) reduction(| : failed) if (n >= DEM_PARALLEL_MIN)
    {
        int t = 0;
#ifdef _OPENMP
        t = omp_get_thread_num();
        int nt = omp_get_num_threads();
#else
        int nt = 1;
#endif
        /* Fixed contiguous ranges per buffer: the concatenation order never changes. */
        for (int b = t; b < nb; b += nt) {
            emit_ctx out = {&s->buffers[b], 0};
            out.out->n = 0;
            s->buffer_overflow[b] = 0;
            size_t lo = n * (size_t)b / (size_t)nb, hi = n * (size_t)(b + 1) / (size_t)nb;
            for (size_t i = lo; i < hi && !failed; i++) {
                out.first = out.out->n;
                if (sphere_sphere(s, &out, i, dt) || sphere_planes(s, &out, i, dt) ||
                    (s->n_meshes && sphere_meshes(s, &out, i, dt, &s->buffer_overflow[b])) ||
                    (s->net.active && sphere_net(s, &out, i, dt, &s->buffer_overflow[b])))
                    failed = 1;
            }
        }
    }
    if (failed) return nc_error_set(err, 1, "dem: out of memory growing the contact list");
    size_t total = 0;
    for (int b = 0; b < nb; b++) {
        if (s->buffer_overflow[b])
            return nc_error_set(err, 1, "dem: a sphere touches more than %d features of one wall "
                                        "mesh or of the net (mesh much finer than the spheres?)",
                                DEM_MAX_FEATURES);
        total += s->buffers[b].n;
    }
    if (nb == 1) { /* the single buffer becomes the list: no copy */
        dem_contacts t = s->contacts;
        s->contacts = s->buffers[0];
        s->buffers[0] = t;
    } else {
        if (dem_contacts_reserve(&s->contacts, total, err)) return -1;
        size_t at[DEM_MAX_BUFFERS + 1];
        at[0] = 0;
        for (int b = 0; b < nb; b++) at[b + 1] = at[b] + s->buffers[b].n;
#pragma omp parallel for schedule(static, 1) num_threads(nb) if (total >= DEM_PARALLEL_MIN)
        for (int b = 0; b < nb; b++) copy_range(&s->contacts, at[b], &s->buffers[b], 0, s->buffers[b].n);
        s->contacts.n = total;
    }

    /* CSR index by sphere (the list is ordered by i) */
    const dem_contacts *c = &s->contacts;
    size_t pos = 0;
    for (size_t i = 0; i <= n; i++) {
        while (pos < total && (size_t)c->i[pos] < i) pos++;
        s->contact_first[i] = (int32_t)pos;
    }

    /* deterministic reduction in contact order */
    memset(s->sph.force, 0, 3 * n * sizeof(double));
    memset(s->sph.torque, 0, 3 * n * sizeof(double));
    memset(s->wall_force, 0, 3 * s->n_walls * sizeof(double));
    if (s->net.active) memset(s->net.force, 0, 3 * s->net.n_nodes * sizeof(double));
    double *net_total = s->wall_force + 3 * (s->n_planes + s->n_meshes);
    for (size_t k = 0; k < total; k++) {
        size_t i = (size_t)c->i[k];
        const double *f = c->force + 3 * k;
        for (int d = 0; d < 3; d++) {
            s->sph.force[3 * i + d] += f[d];
            s->sph.torque[3 * i + d] += c->torque_i[3 * k + d];
        }
        switch (c->kind[k]) {
        case DEM_CONTACT_SPHERE: {
            size_t j = (size_t)c->j[k];
            for (int d = 0; d < 3; d++) {
                s->sph.force[3 * j + d] -= f[d];
                s->sph.torque[3 * j + d] += c->torque_j[3 * k + d];
            }
            break;
        }
        case DEM_CONTACT_PLANE:
            for (int d = 0; d < 3; d++) s->wall_force[3 * (size_t)c->j[k] + d] -= f[d];
            break;
        case DEM_CONTACT_MESH:
            for (int d = 0; d < 3; d++) s->wall_force[3 * (s->n_planes + (size_t)c->aux[k]) + d] -= f[d];
            break;
        case DEM_CONTACT_NET_EDGE: { /* consistent nodal loads: (1-t) f, t f */
            const int32_t *e = s->net.edges + 2 * (size_t)c->j[k];
            double t = c->weight[k];
            for (int d = 0; d < 3; d++) {
                s->net.force[3 * (size_t)e[0] + d] -= (1.0 - t) * f[d];
                s->net.force[3 * (size_t)e[1] + d] -= t * f[d];
                net_total[d] -= f[d];
            }
            break;
        }
        case DEM_CONTACT_NET_NODE:
            for (int d = 0; d < 3; d++) {
                s->net.force[3 * (size_t)c->j[k] + d] -= f[d];
                net_total[d] -= f[d];
            }
            break;
        default:
            break;
        }
    }

    return 0;
}

double dem_contacts_elastic_energy(const dem_sim *s)
{
    const dem_contacts *c = &s->contacts;
    double e = 0.0;
    for (size_t k = 0; k < c->n; k++) {
        size_t i = (size_t)c->i[k];
        dem_pair p;
        switch (c->kind[k]) {
        case DEM_CONTACT_SPHERE: {
            size_t j = (size_t)c->j[k];
            const dem_material *mi = &s->materials[s->sph.material[i]];
            const dem_material *mj = &s->materials[s->sph.material[j]];
            p.e_star = dem_effective_modulus(mi->youngs_modulus_pa, mi->poisson_ratio,
                                             mj->youngs_modulus_pa, mj->poisson_ratio);
            p.r_star = s->sph.radius[i] * s->sph.radius[j] / (s->sph.radius[i] + s->sph.radius[j]);
            break;
        }
        case DEM_CONTACT_PLANE:
            material_wall_pair(s, i, s->planes[c->j[k]].material, &p);
            break;
        case DEM_CONTACT_MESH:
            material_wall_pair(s, i, s->meshes[c->aux[k]].material, &p);
            break;
        default:
            wall_pair(s, i, s->net.youngs_modulus_pa, s->net.poisson_ratio,
                      s->net.shear_modulus_pa, s->net.zeta, s->net.friction, &p);
            break;
        }
        double d = c->overlap[k];
        if (s->prm.law == DEM_LAW_HERTZ_MINDLIN)
            e += 8.0 / 15.0 * p.e_star * sqrt(p.r_star) * pow(d, 2.5); /* ∫ 4/3 E* sqrt(R*) δ^1.5 dδ */
        else
            e += 0.5 * s->prm.linear_kn_n_per_m * d * d;
        const double *ft = c->ft + 3 * k;
        if (c->kt_prev[k] > 0.0) e += 0.5 * (ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2]) / c->kt_prev[k];
    }
    return e;
}
