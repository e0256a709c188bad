/* dem_solver — building, checking and stepping a DEM simulation, coupled sub-stepping through
 * the moving net wall, and save/restore of the complete state for strong coupling. */
#include "dem_solver.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "dem_contact_geometry.h"
#include "dem_contact_hertz.h"
#include "dem_contacts.h"
#include "dem_damping.h"
#include "dem_integrate.h"
#include "dem_stl.h"

void dem_sim_init(dem_sim *s)
{
    memset(s, 0, sizeof *s);
    s->model.prm.gravity[2] = -9.81;
    s->model.prm.dt_auto = 1;
    s->model.prm.dt_safety = 0.1;
    s->model.prm.end_time_s = 1.0;
    s->model.prm.output_interval_s = 0.01;
    s->model.prm.law = DEM_LAW_HERTZ_MINDLIN;
    s->model.prm.damping = DEM_DAMPING_FIT;
    s->model.prm.linear_kt_ratio = 2.0 / 7.0;
    s->model.net.restitution = -1.0;
    s->model.net.zeta = -1.0;
    s->model.net.friction = 0.3;
    s->model.net.poisson_ratio = 0.3;
    s->model.net.near_distance_m = -1.0;
}

static void free_snapshot(dem_snapshot *p)
{
    free(p->body_pos); free(p->body_vel); free(p->body_omega); free(p->body_angmom);
    free(p->body_quat); free(p->sph_pos); free(p->sph_vel); free(p->contact_first);
    free(p->net_cur); free(p->net_vel);
    dem_contacts_free(&p->contacts);
    memset(p, 0, sizeof *p);
}

static void free_net(dem_net *n)
{
    free(n->node_ids); free(n->edges); free(n->ref); free(n->start); free(n->end);
    free(n->end_vel); free(n->cur); free(n->vel); free(n->force); free(n->impulse);
    free(n->box_lo); free(n->box_hi);
    if (n->grid) {
        dem_item_grid_free(n->grid);
        free(n->grid);
    }
    n->node_ids = n->edges = NULL;
    n->ref = n->start = n->end = n->end_vel = n->cur = n->vel = n->force = n->impulse = NULL;
    n->box_lo = n->box_hi = NULL;
    n->grid = NULL;
    n->active = 0;
    n->n_nodes = n->n_edges = 0;
}

void dem_sim_free(dem_sim *s)
{
    free(s->model.materials);
    dem_spheres *p = &s->model.sph;
    free(p->id); free(p->body); free(p->material); free(p->radius); free(p->offset);
    free(p->pos); free(p->vel); free(p->force); free(p->torque);
    dem_bodies *b = &s->model.bod;
    free(b->first_sphere); free(b->n_spheres); free(b->is_cluster); free(b->mass);
    free(b->inv_mass); free(b->inv_inertia_body); free(b->inertia_body); free(b->inv_inertia_iso); free(b->pos);
    free(b->vel); free(b->omega); free(b->angmom); free(b->quat); free(b->force); free(b->torque);
    free(s->model.planes);
    for (size_t m = 0; m < s->model.n_meshes; m++) dem_mesh_free(&s->model.meshes[m]);
    free(s->model.meshes);
    free_net(&s->model.net);
    dem_contacts_free(&s->contact.list);
    dem_contacts_free(&s->contact.prev);
    free(s->contact.first);
    free(s->contact.prev_first);
    free(s->nlist.first);
    free(s->nlist.nbr);
    if (s->nlist.part)
        for (int k = 0; k < s->work.n_buffers; k++) free(s->nlist.part[k].a);
    free(s->nlist.part);
    free(s->nlist.pos_at_build);
    for (int k = 0; k < s->work.n_buffers; k++) dem_contacts_free(&s->work.buffers[k]);
    free(s->work.buffers);
    if (s->work.spills)
        for (int k = 0; k < s->work.n_buffers; k++) free(s->work.spills[k].r);
    free(s->work.spills);
    free(s->work.shared_sphere);
    free(s->work.range_first);
    free(s->contact.wall_pairs);
    free(s->work.overflow);
    dem_cell_grid_free(&s->nlist.grid);
    free(s->wall_force);
    free_snapshot(&s->snap);
    memset(s, 0, sizeof *s);
}

/* ---- building ------------------------------------------------------------------------------- */

#define GROWV(ptr, per, cap)                                                                  \
    do {                                                                                      \
        void *p_ = realloc((ptr), (cap) * (per) * sizeof *(ptr));                             \
        if (!p_) return nc_error_set(err, 1, "dem: out of memory for %zu entries", (size_t)(cap)); \
        (ptr) = p_;                                                                           \
    } while (0)

static int reserve_spheres(dem_sim *s, size_t need, nc_error *err)
{
    dem_spheres *p = &s->model.sph;
    if (need <= p->cap) return 0;
    size_t cap = p->cap ? p->cap : 64;
    while (cap < need) cap *= 2;
    GROWV(p->id, 1, cap); GROWV(p->body, 1, cap); GROWV(p->material, 1, cap);
    GROWV(p->radius, 1, cap); GROWV(p->offset, 3, cap); GROWV(p->pos, 3, cap);
    GROWV(p->vel, 3, cap); GROWV(p->force, 3, cap); GROWV(p->torque, 3, cap);
    p->cap = cap;
    return 0;
}

static int reserve_bodies(dem_sim *s, size_t need, nc_error *err)
{
    dem_bodies *b = &s->model.bod;
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

int dem_sim_add_material(dem_sim *s, const dem_material *m, nc_error *err)
{
    dem_material *p = realloc(s->model.materials, (s->model.n_materials + 1) * sizeof *p);
    if (!p) return nc_error_set(err, 1, "dem: out of memory");
    s->model.materials = p;
    p[s->model.n_materials] = *m;
    return (int)s->model.n_materials++;
}

static int check_material(const dem_sim *s, int material, nc_error *err)
{
    if (material < 0 || (size_t)material >= s->model.n_materials)
        return nc_error_set(err, 1, "dem: material index %d out of range (%zu materials)",
                            material, s->model.n_materials);
    return 0;
}

int dem_sim_add_sphere(dem_sim *s, const double pos[3], double radius, int material,
                       const double vel[3], const double omega[3], nc_error *err)
{
    static const double zero[3] = {0, 0, 0};
    if (!(radius > 0.0) || !isfinite(radius))
        return nc_error_set(err, 1, "dem: sphere radius must be > 0, got %g", radius);
    if (check_material(s, material, err)) return -1;
    if (reserve_spheres(s, s->model.sph.n + 1, err) || reserve_bodies(s, s->model.bod.n + 1, err)) return -1;
    size_t i = s->model.sph.n++, b = s->model.bod.n++;
    s->model.sph.id[i] = (int32_t)i;
    s->model.sph.body[i] = (int32_t)b;
    s->model.sph.material[i] = material;
    s->model.sph.radius[i] = radius;
    memcpy(s->model.sph.offset + 3 * i, zero, sizeof zero);
    memcpy(s->model.sph.pos + 3 * i, pos, 3 * sizeof *pos);
    memcpy(s->model.sph.vel + 3 * i, vel ? vel : zero, 3 * sizeof(double));
    s->model.bod.first_sphere[b] = (int32_t)i;
    s->model.bod.n_spheres[b] = 1;
    s->model.bod.is_cluster[b] = 0;
    memcpy(s->model.bod.pos + 3 * b, pos, 3 * sizeof *pos);
    memcpy(s->model.bod.vel + 3 * b, vel ? vel : zero, 3 * sizeof(double));
    memcpy(s->model.bod.omega + 3 * b, omega ? omega : zero, 3 * sizeof(double));
    double q[4] = {1, 0, 0, 0};
    memcpy(s->model.bod.quat + 4 * b, q, sizeof q);
    memset(s->model.bod.angmom + 3 * b, 0, 3 * sizeof(double));
    return 0;
}

int dem_sim_add_cluster(dem_sim *s, size_t n, const double *pos, const double *radius,
                        int material, const double vel[3], const double omega[3],
                        nc_error *err)
{
    static const double zero[3] = {0, 0, 0};
    if (n == 0) return nc_error_set(err, 1, "dem: a cluster needs at least one sphere");
    if (check_material(s, material, err)) return -1;
    for (size_t k = 0; k < n; k++)
        if (!(radius[k] > 0.0) || !isfinite(radius[k]))
            return nc_error_set(err, 1, "dem: cluster sphere %zu: radius must be > 0, got %g", k,
                                radius[k]);
    if (reserve_spheres(s, s->model.sph.n + n, err) || reserve_bodies(s, s->model.bod.n + 1, err)) return -1;
    size_t b = s->model.bod.n++, first = s->model.sph.n;
    s->model.bod.first_sphere[b] = (int32_t)first;
    s->model.bod.n_spheres[b] = (int32_t)n;
    s->model.bod.is_cluster[b] = 1;
    for (size_t k = 0; k < n; k++) {
        size_t i = s->model.sph.n++;
        s->model.sph.id[i] = (int32_t)i;
        s->model.sph.body[i] = (int32_t)b;
        s->model.sph.material[i] = material;
        s->model.sph.radius[i] = radius[k];
        memcpy(s->model.sph.pos + 3 * i, pos + 3 * k, 3 * sizeof(double));
    }
    memcpy(s->model.bod.vel + 3 * b, vel ? vel : zero, 3 * sizeof(double));
    memcpy(s->model.bod.omega + 3 * b, omega ? omega : zero, 3 * sizeof(double));
    double q[4] = {1, 0, 0, 0};
    memcpy(s->model.bod.quat + 4 * b, q, sizeof q);
    return 0; /* mass, centre, inertia and offsets are derived in dem_sim_prepare */
}

int dem_sim_add_plane(dem_sim *s, const double point[3], const double normal[3],
                      const double velocity[3], int material, nc_error *err)
{
    static const double zero[3] = {0, 0, 0};
    if (check_material(s, material, err)) return -1;
    double len = sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (!(len > 0.0) || !isfinite(len))
        return nc_error_set(err, 1, "dem: plane normal must be a non-zero finite vector");
    dem_plane *p = realloc(s->model.planes, (s->model.n_planes + 1) * sizeof *p);
    if (!p) return nc_error_set(err, 1, "dem: out of memory");
    s->model.planes = p;
    dem_plane *pl = &p[s->model.n_planes++];
    for (int k = 0; k < 3; k++) {
        pl->point0[k] = pl->point[k] = point[k];
        pl->normal[k] = normal[k] / len;
        pl->velocity[k] = velocity ? velocity[k] : zero[k];
    }
    pl->material = material;
    return 0;
}

/* ---- preparation ---------------------------------------------------------------------------- */

static int invert3(const double a[9], double inv[9])
{
    double c00 = a[4] * a[8] - a[5] * a[7], c01 = a[5] * a[6] - a[3] * a[8], c02 = a[3] * a[7] - a[4] * a[6];
    double det = a[0] * c00 + a[1] * c01 + a[2] * c02;
    if (!(fabs(det) > 0.0)) return -1;
    double id = 1.0 / det;
    inv[0] = c00 * id; inv[1] = (a[2] * a[7] - a[1] * a[8]) * id; inv[2] = (a[1] * a[5] - a[2] * a[4]) * id;
    inv[3] = c01 * id; inv[4] = (a[0] * a[8] - a[2] * a[6]) * id; inv[5] = (a[2] * a[3] - a[0] * a[5]) * id;
    inv[6] = c02 * id; inv[7] = (a[1] * a[6] - a[0] * a[7]) * id; inv[8] = (a[0] * a[4] - a[1] * a[3]) * id;
    return 0;
}

static void body_mass_properties(dem_sim *s, size_t b)
{
    dem_bodies *B = &s->model.bod;
    int32_t first = B->first_sphere[b], count = B->n_spheres[b];
    double M = 0.0, com[3] = {0, 0, 0};
    for (int32_t q = first; q < first + count; q++) {
        double r = s->model.sph.radius[q];
        double m = 4.0 / 3.0 * M_PI * r * r * r * s->model.materials[s->model.sph.material[q]].density_kg_m3;
        M += m;
        for (int k = 0; k < 3; k++) com[k] += m * s->model.sph.pos[3 * (size_t)q + k];
    }
    for (int k = 0; k < 3; k++) com[k] /= M;
    double I[9] = {0};
    for (int32_t q = first; q < first + count; q++) {
        double r = s->model.sph.radius[q];
        double m = 4.0 / 3.0 * M_PI * r * r * r * s->model.materials[s->model.sph.material[q]].density_kg_m3;
        double d[3];
        for (int k = 0; k < 3; k++) d[k] = s->model.sph.pos[3 * (size_t)q + k] - com[k];
        double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        for (int a = 0; a < 3; a++)
            for (int c = 0; c < 3; c++)
                I[3 * a + c] += (a == c ? 0.4 * m * r * r + m * d2 : 0.0) - m * d[a] * d[c];
        if (B->is_cluster[b]) memcpy(s->model.sph.offset + 3 * (size_t)q, d, sizeof d);
    }
    B->mass[b] = M;
    B->inv_mass[b] = 1.0 / M;
    memcpy(B->inertia_body + 9 * b, I, sizeof I);
    if (B->is_cluster[b]) {
        memcpy(B->pos + 3 * b, com, sizeof com);
        invert3(I, B->inv_inertia_body + 9 * b); /* each sphere adds 2/5 m r² 1: invertible */
        B->inv_inertia_iso[b] = 0.0;
        const double *w = B->omega + 3 * b;
        for (int a = 0; a < 3; a++)
            B->angmom[3 * b + a] = I[3 * a] * w[0] + I[3 * a + 1] * w[1] + I[3 * a + 2] * w[2];
    } else {
        double *inv = B->inv_inertia_body + 9 * b;
        memset(inv, 0, 9 * sizeof *inv);
        inv[0] = inv[4] = inv[8] = 1.0 / I[0];
        B->inv_inertia_iso[b] = inv[0];
    }
}

double dem_sim_critical_dt(const dem_sim *s)
{
    double crit = INFINITY;
    if (s->model.prm.law == DEM_LAW_HERTZ_MINDLIN) {
        /* Rayleigh wave time step: π R sqrt(ρ/G) / (0.1631 ν + 0.8766) */
        for (size_t i = 0; i < s->model.sph.n; i++) {
            const dem_material *m = &s->model.materials[s->model.sph.material[i]];
            double t = M_PI * s->model.sph.radius[i] * sqrt(m->density_kg_m3 / m->shear_modulus_pa) /
                       (0.1631 * m->poisson_ratio + 0.8766);
            if (t < crit) crit = t;
        }
    } else {
        /* stability of the spring between the two lightest bodies: 2 sqrt(m_star / k) */
        for (size_t b = 0; b < s->model.bod.n; b++) {
            double t = 2.0 * sqrt(0.5 * s->model.bod.mass[b] / s->model.prm.linear_kn_n_per_m);
            if (t < crit) crit = t;
        }
    }
    return crit;
}

/* Hertz contact duration t_c = 2.87 (m*² / (R* E*² v))^(1/5) for the lightest, smallest
 * sphere against the stiffest partner at the impact speed v. */
static double hertz_contact_time(const dem_sim *s, double v)
{
    double tc = INFINITY;
    for (size_t i = 0; i < s->model.sph.n; i++) {
        const dem_material *m = &s->model.materials[s->model.sph.material[i]];
        double e_max = dem_effective_modulus(m->youngs_modulus_pa, m->poisson_ratio,
                                             m->youngs_modulus_pa, m->poisson_ratio);
        for (size_t k = 0; k < s->model.n_materials; k++) {
            const dem_material *w = &s->model.materials[k];
            double e = dem_effective_modulus(m->youngs_modulus_pa, m->poisson_ratio,
                                             w->youngs_modulus_pa, w->poisson_ratio);
            if (e > e_max) e_max = e;
        }
        if (s->model.net.youngs_modulus_pa > 0.0) {
            double e = dem_effective_modulus(m->youngs_modulus_pa, m->poisson_ratio,
                                             s->model.net.youngs_modulus_pa, s->model.net.poisson_ratio);
            if (e > e_max) e_max = e;
        }
        double mstar = 0.5 * s->model.bod.mass[s->model.sph.body[i]], r = 0.5 * s->model.sph.radius[i];
        double t = 2.87 * pow(mstar * mstar / (r * e_max * e_max * v), 0.2);
        if (t < tc) tc = t;
    }
    return tc;
}

static int check_overlaps(dem_sim *s, nc_error *err)
{
    if (s->model.sph.n < 2) return 0;
    if (dem_cell_grid_build(&s->nlist.grid, s->model.sph.n, s->model.sph.pos, 2.0 * s->model.r_max, err)) return -1;
    const dem_cell_grid *g = &s->nlist.grid;
    for (size_t i = 0; i < s->model.sph.n; i++) {
        int c[3];
        dem_cell_grid_coords(g, s->model.sph.pos + 3 * i, c);
        for (int dz = -1; dz <= 1; dz++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) {
                    int x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
                    if (x < 0 || y < 0 || z < 0 || x >= g->dims[0] || y >= g->dims[1] || z >= g->dims[2]) continue;
                    size_t cell = ((size_t)z * (size_t)g->dims[1] + (size_t)y) * (size_t)g->dims[0] + (size_t)x;
                    for (int32_t q = g->cell_start[cell]; q < g->cell_start[cell + 1]; q++) {
                        size_t j = (size_t)g->cell_items[q];
                        if (j <= i || s->model.sph.body[j] == s->model.sph.body[i]) continue;
                        double d2 = 0.0;
                        for (int k = 0; k < 3; k++) {
                            double d = s->model.sph.pos[3 * j + k] - s->model.sph.pos[3 * i + k];
                            d2 += d * d;
                        }
                        double rs = s->model.sph.radius[i] + s->model.sph.radius[j];
                        /* a tiny tolerance lets lattices touch exactly */
                        if (d2 < rs * rs * (1.0 - 1e-9))
                            return nc_error_set(err, 1, "%s: particles %d and %d overlap at the "
                                                "start (distance %g m < sum of radii %g m)",
                                                s->model.source[0] ? s->model.source : "dem", s->model.sph.id[i],
                                                s->model.sph.id[j], sqrt(d2), rs);
                    }
                }
    }
    return 0;
}

int dem_sim_prepare(dem_sim *s, nc_error *err)
{
    if (s->model.n_materials == 0) return nc_error_set(err, 1, "%s: no materials", s->model.source);
    /* arrays exist even without particles (memcpy/memset never see NULL) */
    if (reserve_spheres(s, 1, err) || reserve_bodies(s, 1, err)) return -1;
    if (s->model.prm.law == DEM_LAW_LINEAR && !(s->model.prm.linear_kn_n_per_m > 0.0))
        return nc_error_set(err, 1, "%s: the linear contact law needs "
                                    "linear.normal_stiffness_n_per_m > 0", s->model.source);
    for (size_t k = 0; k < s->model.n_materials; k++) {
        dem_material *m = &s->model.materials[k];
        m->shear_modulus_pa = m->youngs_modulus_pa / (2.0 * (1.0 + m->poisson_ratio));
        m->zeta = s->model.prm.damping == DEM_DAMPING_FIT ? dem_zeta_fit(m->restitution)
                                                    : dem_zeta_a7(m->restitution);
        m->pair_e_star = dem_effective_modulus(m->youngs_modulus_pa, m->poisson_ratio,
                                               m->youngs_modulus_pa, m->poisson_ratio);
        m->pair_g_star = dem_effective_shear(m->shear_modulus_pa, m->poisson_ratio,
                                             m->shear_modulus_pa, m->poisson_ratio);
        m->pair_kt_kn_root = s->model.prm.law == DEM_LAW_HERTZ_MINDLIN
                                 ? sqrt(4.0 * m->pair_g_star / m->pair_e_star)
                                 : sqrt(s->model.prm.linear_kt_ratio);
    }
    dem_net *net = &s->model.net;
    if (net->youngs_modulus_pa > 0.0)
        net->shear_modulus_pa = net->youngs_modulus_pa / (2.0 * (1.0 + net->poisson_ratio));
    if (net->restitution >= 0.0)
        net->zeta = s->model.prm.damping == DEM_DAMPING_FIT ? dem_zeta_fit(net->restitution)
                                                      : dem_zeta_a7(net->restitution);
    s->model.r_max = 0.0;
    s->model.r_min = INFINITY;
    for (size_t i = 0; i < s->model.sph.n; i++) {
        if (s->model.sph.radius[i] > s->model.r_max) s->model.r_max = s->model.sph.radius[i];
        if (s->model.sph.radius[i] < s->model.r_min) s->model.r_min = s->model.sph.radius[i];
    }
    if (s->model.sph.n == 0) s->model.r_min = s->model.r_max = 1.0;
    if (net->near_distance_m < 0.0) net->near_distance_m = s->model.r_max;
    for (size_t b = 0; b < s->model.bod.n; b++) body_mass_properties(s, b);
    if (check_overlaps(s, err)) return -1;
    dem_update_spheres(s);

    if (s->model.prm.dt_auto) {
        double dt = s->model.prm.dt_safety * dem_sim_critical_dt(s);
        if (s->model.prm.law == DEM_LAW_HERTZ_MINDLIN && s->model.sph.n > 0) {
            double vmax = 0.0;
            for (size_t b = 0; b < s->model.bod.n; b++) {
                const double *v = s->model.bod.vel + 3 * b;
                double sp = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                if (sp > vmax) vmax = sp;
            }
            double vref = fmax(1.0, 2.0 * vmax);
            double tc = hertz_contact_time(s, vref) / 40.0; /* >= 40 steps per impact */
            if (tc < dt) dt = tc;
        }
        if (!isfinite(dt) || !(dt > 0.0)) dt = 1e-4;
        s->model.prm.dt_s = dt;
    }

    /* step storage */
    int nb = s->model.prm.threads > 0 ? s->model.prm.threads : 1;
#ifdef _OPENMP
    if (s->model.prm.threads <= 0) nb = omp_get_max_threads();
#endif
    if (nb < 1) nb = 1;
    if (nb > DEM_MAX_BUFFERS) nb = DEM_MAX_BUFFERS;
    s->work.n_buffers = nb;
    s->work.buffers = calloc((size_t)nb, sizeof *s->work.buffers);
    s->work.overflow = calloc((size_t)nb, sizeof *s->work.overflow);
    s->work.spills = calloc((size_t)nb, sizeof *s->work.spills);
    s->nlist.part = calloc((size_t)nb, sizeof *s->nlist.part);
    size_t n = s->model.sph.n;
    s->work.shared_sphere = calloc(n + 1, sizeof *s->work.shared_sphere);
    s->work.range_first = malloc(((size_t)nb + 1) * sizeof *s->work.range_first);
    if (s->work.range_first)
        for (int b = 0; b <= nb; b++) s->work.range_first[b] = n * (size_t)b / (size_t)nb;
    s->contact.first = calloc(n + 1, sizeof *s->contact.first);
    s->nlist.first = calloc(n + 1, sizeof *s->nlist.first);
    s->nlist.pos_at_build = malloc((3 * n + 1) * sizeof *s->nlist.pos_at_build);
    if (!(s->nlist.skin_m > 0.0)) s->nlist.skin_m = 0.2 * s->model.r_min;
    s->nlist.rebuild = 1;
    s->contact.prev_first = calloc(n + 1, sizeof *s->contact.prev_first);
    s->n_walls = s->model.n_planes + s->model.n_meshes + 1;
    s->wall_force = calloc(3 * s->n_walls, sizeof *s->wall_force);
    dem_snapshot *p = &s->snap;
    size_t nbod = s->model.bod.n ? s->model.bod.n : 1, nsph = n ? n : 1;
    p->body_pos = malloc(3 * nbod * sizeof(double));
    p->body_vel = malloc(3 * nbod * sizeof(double));
    p->body_omega = malloc(3 * nbod * sizeof(double));
    p->body_angmom = malloc(3 * nbod * sizeof(double));
    p->body_quat = malloc(4 * nbod * sizeof(double));
    p->sph_pos = malloc(3 * nsph * sizeof(double));
    p->sph_vel = malloc(3 * nsph * sizeof(double));
    p->contact_first = malloc((n + 1) * sizeof(int32_t));
    if (!s->work.buffers || !s->work.overflow || !s->work.spills || !s->nlist.part || !s->work.shared_sphere || !s->work.range_first || !s->contact.first || !s->contact.prev_first ||
        !s->nlist.first || !s->nlist.pos_at_build ||
        !s->wall_force || !p->body_pos || !p->body_vel || !p->body_omega || !p->body_angmom ||
        !p->body_quat || !p->sph_pos || !p->sph_vel || !p->contact_first)
        return nc_error_set(err, 1, "dem: out of memory for %zu spheres", n);
    size_t guess = 8 * n / (size_t)nb + 64;
    for (int k = 0; k < nb; k++)
        if (dem_contacts_reserve(&s->work.buffers[k], guess, err)) return -1;
    if (dem_contacts_reserve(&s->contact.list, 8 * n + 64, err) ||
        dem_contacts_reserve(&s->contact.prev, 8 * n + 64, err))
        return -1;
    if (dem_contacts_prepare(s, err)) return -1;
    s->prepared = 1;
    return 0;
}

/* ---- stepping ------------------------------------------------------------------------------- */

int dem_sim_step(dem_sim *s, double dt, nc_error *err)
{
    for (size_t w = 0; w < s->model.n_planes; w++)
        for (int k = 0; k < 3; k++)
            s->model.planes[w].point[k] = s->model.planes[w].point0[k] + s->model.planes[w].velocity[k] * s->time_s;
    for (size_t m = 0; m < s->model.n_meshes; m++)
        for (int k = 0; k < 3; k++) s->model.meshes[m].offset[k] = s->model.meshes[m].velocity[k] * s->time_s;
    if (dem_compute_contacts(s, dt, err)) return -1;
    dem_integrate_bodies(s, dt);
    s->time_s += dt;
    s->step++;
    return 0;
}

/* ---- net wall ------------------------------------------------------------------------------- */

static int build_net_grid(dem_sim *s, nc_error *err)
{
    dem_net *net = &s->model.net;
    for (size_t e = 0; e < net->n_edges; e++) {
        const double *a = net->cur + 3 * (size_t)net->edges[2 * e];
        const double *b = net->cur + 3 * (size_t)net->edges[2 * e + 1];
        for (int k = 0; k < 3; k++) {
            net->box_lo[3 * e + k] = fmin(a[k], b[k]);
            net->box_hi[3 * e + k] = fmax(a[k], b[k]);
        }
    }
    double inflate = s->model.r_max + net->cable_radius_m + net->near_distance_m;
    return dem_item_grid_build(net->grid, net->n_edges, net->box_lo, net->box_hi, inflate, err);
}

int dem_sim_set_interface(dem_sim *s, size_t n_nodes, const int32_t *node_ids,
                          const double *coords, size_t n_edges, const int32_t *edges,
                          nc_error *err)
{
    if (!s->prepared) return nc_error_set(err, 1, "dem: interface before the model was prepared");
    if (!(s->model.net.youngs_modulus_pa > 0.0))
        return nc_error_set(err, 1, "%s: net_wall: the coupled net wall needs net_wall."
                                    "youngs_modulus_pa > 0", s->model.source);
    if (n_nodes == 0) return nc_error_set(err, 1, "interface: no nodes");
    if (n_edges == 0) return nc_error_set(err, 1, "interface: no elements");
    for (size_t k = 0; k < 3 * n_nodes; k++)
        if (!isfinite(coords[k]))
            return nc_error_set(err, 1, "interface: coordinates[%zu] is not finite", k / 3);
    for (size_t e = 0; e < n_edges; e++) {
        int32_t a = edges[2 * e], b = edges[2 * e + 1];
        if (a < 0 || b < 0 || (size_t)a >= n_nodes || (size_t)b >= n_nodes)
            return nc_error_set(err, 1, "interface: elements[%zu] = [%d, %d]: node index out of "
                                        "range 0..%zu", e, a, b, n_nodes - 1);
        if (a == b)
            return nc_error_set(err, 1, "interface: elements[%zu] joins node %d to itself", e, a);
    }
    dem_net *net = &s->model.net;
    free_net(net);
    net->n_nodes = n_nodes;
    net->n_edges = n_edges;
    net->node_ids = malloc(n_nodes * sizeof(int32_t));
    net->edges = malloc(2 * n_edges * sizeof(int32_t));
    double **arrays[] = {&net->ref, &net->start, &net->end, &net->end_vel, &net->cur,
                         &net->vel, &net->force, &net->impulse};
    int ok = net->node_ids && net->edges;
    for (size_t k = 0; k < sizeof arrays / sizeof *arrays; k++) {
        *arrays[k] = calloc(3 * n_nodes, sizeof(double));
        ok = ok && *arrays[k];
    }
    net->box_lo = malloc(3 * n_edges * sizeof(double));
    net->box_hi = malloc(3 * n_edges * sizeof(double));
    net->grid = calloc(1, sizeof *net->grid);
    dem_snapshot *p = &s->snap;
    free(p->net_cur);
    free(p->net_vel);
    p->net_cur = malloc(3 * n_nodes * sizeof(double));
    p->net_vel = malloc(3 * n_nodes * sizeof(double));
    p->net_nodes = n_nodes;
    if (!ok || !net->box_lo || !net->box_hi || !net->grid || !p->net_cur || !p->net_vel)
        return nc_error_set(err, 1, "dem: out of memory for the interface (%zu nodes)", n_nodes);
    for (size_t k = 0; k < n_nodes; k++) net->node_ids[k] = node_ids ? node_ids[k] : (int32_t)k;
    memcpy(net->edges, edges, 2 * n_edges * sizeof(int32_t));
    memcpy(net->ref, coords, 3 * n_nodes * sizeof(double));
    memcpy(net->start, coords, 3 * n_nodes * sizeof(double));
    memcpy(net->end, coords, 3 * n_nodes * sizeof(double));
    memcpy(net->cur, coords, 3 * n_nodes * sizeof(double));
    net->active = 1;
    s->snap.valid = 0;
    return build_net_grid(s, err);
}

int dem_sim_begin_step(dem_sim *s, nc_error *err)
{
    dem_snapshot *p = &s->snap;
    size_t nb = s->model.bod.n, n = s->model.sph.n;
    memcpy(p->body_pos, s->model.bod.pos, 3 * nb * sizeof(double));
    memcpy(p->body_vel, s->model.bod.vel, 3 * nb * sizeof(double));
    memcpy(p->body_omega, s->model.bod.omega, 3 * nb * sizeof(double));
    memcpy(p->body_angmom, s->model.bod.angmom, 3 * nb * sizeof(double));
    memcpy(p->body_quat, s->model.bod.quat, 4 * nb * sizeof(double));
    memcpy(p->sph_pos, s->model.sph.pos, 3 * n * sizeof(double));
    memcpy(p->sph_vel, s->model.sph.vel, 3 * n * sizeof(double));
    if (dem_contacts_copy(&p->contacts, &s->contact.list, err)) return -1;
    memcpy(p->contact_first, s->contact.first, (n + 1) * sizeof(int32_t));
    if (s->model.net.active) {
        memcpy(s->model.net.start, s->model.net.cur, 3 * s->model.net.n_nodes * sizeof(double));
        memcpy(p->net_cur, s->model.net.cur, 3 * s->model.net.n_nodes * sizeof(double));
        memcpy(p->net_vel, s->model.net.vel, 3 * s->model.net.n_nodes * sizeof(double));
    }
    p->time_s = s->time_s;
    p->step = s->step;
    p->valid = 1;
    s->nlist.rebuild = 1; /* the repeated step (after a restore) rebuilds at this same state */
    return 0;
}

int dem_sim_restore(dem_sim *s, nc_error *err)
{
    dem_snapshot *p = &s->snap;
    if (!p->valid) return nc_error_set(err, 1, "dem: restore requested but no step was begun");
    size_t nb = s->model.bod.n, n = s->model.sph.n;
    memcpy(s->model.bod.pos, p->body_pos, 3 * nb * sizeof(double));
    memcpy(s->model.bod.vel, p->body_vel, 3 * nb * sizeof(double));
    memcpy(s->model.bod.omega, p->body_omega, 3 * nb * sizeof(double));
    memcpy(s->model.bod.angmom, p->body_angmom, 3 * nb * sizeof(double));
    memcpy(s->model.bod.quat, p->body_quat, 4 * nb * sizeof(double));
    memcpy(s->model.sph.pos, p->sph_pos, 3 * n * sizeof(double));
    memcpy(s->model.sph.vel, p->sph_vel, 3 * n * sizeof(double));
    if (dem_contacts_copy(&s->contact.list, &p->contacts, err)) return -1;
    memcpy(s->contact.first, p->contact_first, (n + 1) * sizeof(int32_t));
    if (s->model.net.active && p->net_nodes == s->model.net.n_nodes) {
        memcpy(s->model.net.cur, p->net_cur, 3 * s->model.net.n_nodes * sizeof(double));
        memcpy(s->model.net.vel, p->net_vel, 3 * s->model.net.n_nodes * sizeof(double));
        memcpy(s->model.net.start, p->net_cur, 3 * s->model.net.n_nodes * sizeof(double));
    }
    s->time_s = p->time_s;
    s->step = p->step;
    s->nlist.rebuild = 1;
    return 0;
}

void dem_sim_net_gap(const dem_sim *s, dem_coupled_info *info)
{
    const dem_net *net = &s->model.net;
    double gap = 1e30;
    long n = (long)s->model.sph.n;
    if (net->active) {
#pragma omp parallel for schedule(static) reduction(min : gap) num_threads(s->work.n_buffers) if (n >= DEM_PARALLEL_MIN)
        for (long i = 0; i < n; i++) {
            const double *p = s->model.sph.pos + 3 * i;
            const int32_t *items;
            size_t count = dem_item_grid_query(net->grid, p, &items);
            for (size_t c = 0; c < count; c++) {
                const int32_t *e = net->edges + 2 * (size_t)items[c];
                double q[3], t;
                double d2 = dem_closest_on_segment(p, net->cur + 3 * (size_t)e[0],
                                                   net->cur + 3 * (size_t)e[1], q, &t);
                double g = sqrt(d2) - s->model.sph.radius[i] - net->cable_radius_m;
                if (g < gap) gap = g;
            }
        }
    }
    info->min_gap_m = gap;
    info->near_interface = gap < net->near_distance_m;
    long contacts = 0;
    for (size_t k = 0; k < s->contact.list.n; k++)
        contacts += s->contact.list.kind[k] == DEM_CONTACT_NET_EDGE || s->contact.list.kind[k] == DEM_CONTACT_NET_NODE;
    info->contacts = contacts;
}

/* Algorithm 1's larger step: when no sphere can reach another sphere, a plane or the net
 * during the whole coupling step (travel bound |v| dt + ½ |g| dt² + rotation sweep), the
 * bodies fly ballistically in one exact step instead of sub-stepping. Not with STL meshes
 * (their grid only reaches contact distance). Sets *done when it was applied. */
static int try_free_flight(dem_sim *s, double dt, long substeps, int *done, nc_error *err)
{
    *done = 0;
    if (!s->model.prm.free_flight || s->model.n_meshes > 0 || s->model.sph.n == 0) return 0;
    const double *g = s->model.prm.gravity;
    double gmag = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]), travel = 0.0;
    for (size_t b = 0; b < s->model.bod.n; b++) {
        const double *v = s->model.bod.vel + 3 * b, *w = s->model.bod.omega + 3 * b;
        double d = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * dt + 0.5 * gmag * dt * dt;
        if (s->model.bod.is_cluster[b]) {
            double reach = 0.0;
            for (int32_t q = s->model.bod.first_sphere[b]; q < s->model.bod.first_sphere[b] + s->model.bod.n_spheres[b]; q++) {
                const double *o = s->model.sph.offset + 3 * (size_t)q;
                reach = fmax(reach, sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]));
            }
            d += fmin(sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) * dt, 2.0) * reach;
        }
        travel = fmax(travel, d);
    }
    double margin = 1e-6 * travel + 1e-12;
    /* planes (they may move too) */
    for (size_t i = 0; i < s->model.sph.n; i++) {
        const double *p = s->model.sph.pos + 3 * i;
        for (size_t w = 0; w < s->model.n_planes; w++) {
            const dem_plane *pl = &s->model.planes[w];
            double d = (p[0] - pl->point[0]) * pl->normal[0] + (p[1] - pl->point[1]) * pl->normal[1] +
                       (p[2] - pl->point[2]) * pl->normal[2];
            double vp = sqrt(pl->velocity[0] * pl->velocity[0] + pl->velocity[1] * pl->velocity[1] +
                             pl->velocity[2] * pl->velocity[2]);
            if (d > -s->model.sph.radius[i] && d - s->model.sph.radius[i] <= travel + vp * dt + margin) return 0;
        }
    }
    /* the net: gap at the start against sphere travel plus the largest node motion */
    dem_net *net = &s->model.net;
    double node_move = 0.0;
    for (size_t k = 0; k < net->n_nodes; k++) {
        double d[3] = {net->end[3 * k] - net->start[3 * k], net->end[3 * k + 1] - net->start[3 * k + 1],
                       net->end[3 * k + 2] - net->start[3 * k + 2]};
        node_move = fmax(node_move, sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
    }
    dem_coupled_info gap;
    dem_sim_net_gap(s, &gap);
    double net_gap = gap.min_gap_m < 1e29 ? gap.min_gap_m : net->near_distance_m;
    if (net_gap <= travel + node_move + margin) return 0;
    /* sphere pairs */
    long close;
    if (dem_contacts_close_pairs(s, 2.0 * travel + margin, &close, err)) return -1;
    if (close > 0) return 0;

    dem_free_flight(s, dt, substeps);
    s->time_s += dt;
    s->step++;
    s->contact.list.n = 0;
    memset(s->contact.first, 0, (s->model.sph.n + 1) * sizeof *s->contact.first);
    memset(s->wall_force, 0, 3 * s->n_walls * sizeof *s->wall_force);
    memset(net->force, 0, 3 * net->n_nodes * sizeof *net->force);
    *done = 1;
    return 0;
}

int dem_sim_solve_coupled(dem_sim *s, double dt_step, const double *disp_end,
                          const double *vel_end, double *force_out, dem_coupled_info *info,
                          nc_error *err)
{
    dem_net *net = &s->model.net;
    if (!net->active) return nc_error_set(err, 1, "dem: solve before the interface was received");
    if (!(dt_step > 0.0) || !isfinite(dt_step))
        return nc_error_set(err, 1, "dem: coupling step dt_s must be > 0, got %g", dt_step);
    size_t nn = net->n_nodes;
    for (size_t k = 0; k < 3 * nn; k++) {
        if (!isfinite(disp_end[k]) || (vel_end && !isfinite(vel_end[k])))
            return nc_error_set(err, 1, "dem: interface displacement/velocity of node %zu is not "
                                        "finite", k / 3);
        net->end[k] = net->ref[k] + disp_end[k];
        net->end_vel[k] = vel_end ? vel_end[k] : 0.0;
    }
    double ratio = dt_step / s->model.prm.dt_s;
    long substeps = (long)ceil(ratio - 1e-9);
    if (substeps < 1) substeps = 1;
    double h = dt_step / (double)substeps;
    memset(net->impulse, 0, 3 * nn * sizeof(double));
    /* the wall moves linearly from start to end: constant velocity over the step */
    for (size_t k = 0; k < 3 * nn; k++) net->vel[k] = (net->end[k] - net->start[k]) / dt_step;
    memcpy(net->cur, net->start, 3 * nn * sizeof(double));
    int flown = 0;
    if (substeps > 1) {
        if (build_net_grid(s, err) || try_free_flight(s, dt_step, substeps, &flown, err)) return -1;
        if (flown) substeps = 0; /* reported as 1 step below */
    }
    for (long sub = 0; sub < substeps; sub++) {
        /* The wall is placed where it is at the END of the sub-step (default): the last
         * sub-step uses exactly the position the FEM returned, so even a single sub-step
         * responds to the iterated interface position (strong coupling then is implicit on the
         * interface instead of silently degenerating to the weak scheme). With wall_position
         * "middle" it is where it is at the middle of the sub-step: centred in time, the
         * average force then belongs to the whole step, which is what a structure applying it
         * over the whole step (fem_solver coupling_load "step_constant") needs to exchange
         * energy without creating any (scripts/diagnostics/centred_coupling.md). */
        double frac = ((double)sub + (net->wall_at_middle ? 0.5 : 1.0)) / (double)substeps;
        for (size_t k = 0; k < 3 * nn; k++)
            net->cur[k] = net->start[k] + frac * (net->end[k] - net->start[k]);
        if (build_net_grid(s, err)) return -1;
        if (dem_sim_step(s, h, err)) return -1;
        for (size_t k = 0; k < 3 * nn; k++) net->impulse[k] += h * net->force[k];
    }
    memcpy(net->cur, net->end, 3 * nn * sizeof(double));
    if (build_net_grid(s, err)) return -1;
    if (net->force_at_end) {
        /* The force of the last sub-step, whose wall is at its end-of-step position (see the
         * loop above): the load at t_n+1 that a structure with equilibrium at t_n+1 (Newmark,
         * Bossak) needs, and the force the particles received last. The step average stands
         * for the middle of the step: applied as the t_n+1 load it lags the wall by about
         * dt/2, a delayed contact spring that pumps energy into a light net
         * (scripts/diagnostics/rest_position.md). After a free flight nothing touches the net
         * and net->force is zero. */
        memcpy(force_out, net->force, 3 * nn * sizeof(double));
    } else {
        for (size_t k = 0; k < 3 * nn; k++) force_out[k] = net->impulse[k] / dt_step;
    }
    dem_sim_net_gap(s, info);
    info->substeps = flown ? 1 : substeps;
    return 0;
}

/* ---- diagnostics ---------------------------------------------------------------------------- */

double dem_sim_kinetic_energy(const dem_sim *s)
{
    double e = 0.0;
    for (size_t b = 0; b < s->model.bod.n; b++) {
        const double *v = s->model.bod.vel + 3 * b, *w = s->model.bod.omega + 3 * b;
        e += 0.5 * s->model.bod.mass[b] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (s->model.bod.is_cluster[b]) {
            const double *L = s->model.bod.angmom + 3 * b;
            e += 0.5 * (w[0] * L[0] + w[1] * L[1] + w[2] * L[2]);
        } else {
            e += 0.5 * s->model.bod.inertia_body[9 * b] * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        }
    }
    return e;
}

double dem_sim_potential_energy(const dem_sim *s)
{
    double e = 0.0;
    const double *g = s->model.prm.gravity;
    for (size_t b = 0; b < s->model.bod.n; b++) {
        const double *x = s->model.bod.pos + 3 * b;
        e -= s->model.bod.mass[b] * (g[0] * x[0] + g[1] * x[1] + g[2] * x[2]);
    }
    return e;
}
