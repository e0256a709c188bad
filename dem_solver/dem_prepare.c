/* dem_prepare — completing a built model and allocating the step storage: material
 * properties and damping ratios, body mass properties (summed from the spheres, or given for a
 * cluster: dem_mass_override, checked by dem_inertia_check), the overlap checks at the start
 * (spheres with spheres, planes and meshes),
 * the critical time step and the contact time of the contact law (dem_contact_law.h) that
 * limit an automatic dt. */
#include "dem_sim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "dem_contact_geometry.h"
#include "dem_contact_hertz.h"
#include "dem_contact_law.h"
#include "dem_damping.h"
#include "dem_integrate.h"
#include "dem_neighbor_grid.h"

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

/* Eigenvalues of a symmetric 3×3 matrix by cyclic Jacobi rotations (converges quadratically;
 * 50 sweeps are far more than a 3×3 needs), ascending. */
static void symmetric_eigenvalues(const double m[9], double lambda[3])
{
    double a[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) a[i][j] = 0.5 * (m[3 * i + j] + m[3 * j + i]);
    for (int sweep = 0; sweep < 50; sweep++) {
        double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
        double diag = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
        if (!(off > 1e-300) || off <= 1e-17 * diag) break;
        for (int p = 0; p < 2; p++)
            for (int q = p + 1; q < 3; q++) {
                if (a[p][q] == 0.0) continue;
                double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), sn = t * c;
                for (int k = 0; k < 3; k++) { /* columns p, q */
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - sn * akq;
                    a[k][q] = sn * akp + c * akq;
                }
                for (int k = 0; k < 3; k++) { /* rows p, q */
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - sn * aqk;
                    a[q][k] = sn * apk + c * aqk;
                }
            }
    }
    lambda[0] = a[0][0];
    lambda[1] = a[1][1];
    lambda[2] = a[2][2];
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2 - i; j++)
            if (lambda[j] > lambda[j + 1]) {
                double t = lambda[j];
                lambda[j] = lambda[j + 1];
                lambda[j + 1] = t;
            }
}

int dem_inertia_check(const double inertia[9], double principal[3], nc_error *err)
{
    double big = 0.0;
    for (int k = 0; k < 9; k++) {
        if (!isfinite(inertia[k]))
            return nc_error_set(err, 1, "entry [%d][%d] is not a finite number", k / 3, k % 3);
        big = fmax(big, fabs(inertia[k]));
    }
    for (int a = 0; a < 3; a++)
        for (int c = a + 1; c < 3; c++)
            if (fabs(inertia[3 * a + c] - inertia[3 * c + a]) > 1e-9 * big)
                return nc_error_set(err, 1, "not symmetric: [%d][%d] = %.10g but [%d][%d] = %.10g",
                                    a, c, inertia[3 * a + c], c, a, inertia[3 * c + a]);
    double l[3];
    symmetric_eigenvalues(inertia, l);
    if (!(l[0] > 1e-9 * l[2]))
        return nc_error_set(err, 1, "not positive definite: principal moments %.6g, %.6g, %.6g "
                                    "kg m² (each must be > 0)", l[0], l[1], l[2]);
    /* I3 = ∫(x² + y²) dm <= ∫(x² + z²) dm + ∫(y² + z²) dm = I2 + I1 for any mass distribution */
    if (l[2] > (l[0] + l[1]) * (1.0 + 1e-9))
        return nc_error_set(err, 1, "no body has these principal moments %.6g, %.6g, %.6g kg m²: "
                                    "the largest exceeds the sum of the other two (triangle "
                                    "inequality)", l[0], l[1], l[2]);
    if (principal) memcpy(principal, l, sizeof l);
    return 0;
}

/* Mass, centre of mass, inertia and sphere offsets of body b: summed from its spheres (each
 * sphere's volume times its density), then replaced by the given values `o` (may be NULL).
 * Everything is in the world frame at t = 0, the body frame (orientation is the identity). */
static void body_mass_properties(dem_sim *s, size_t b, const dem_mass_override *o)
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
    if (o && o->full) {
        /* the given body: centre and inertia as given; offsets from the given centre */
        memcpy(com, o->com, sizeof com);
        memcpy(I, o->inertia, sizeof I);
        for (int32_t q = first; q < first + count; q++)
            for (int k = 0; k < 3; k++)
                s->model.sph.offset[3 * (size_t)q + k] = s->model.sph.pos[3 * (size_t)q + k] - com[k];
    } else if (o) {
        /* the spheres' shape at the given mass: a uniform density scale */
        for (int k = 0; k < 9; k++) I[k] *= o->mass_kg / M;
    }
    if (o) M = o->mass_kg;
    B->mass[b] = M;
    B->inv_mass[b] = 1.0 / M;
    memcpy(B->inertia_body + 9 * b, I, sizeof I);
    if (B->is_cluster[b]) {
        memcpy(B->pos + 3 * b, com, sizeof com);
        invert3(I, B->inv_inertia_body + 9 * b); /* each sphere adds 2/5 m r² 1, a given
                                                    tensor is positive definite: invertible */
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
    return dem_contact_law_of(s->model.prm.law)->critical_dt(s);
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

/* Nor may a sphere start inside a wall: a plane or mesh overlapping it by more than round-off
 * throws it out with the force of the whole overlap at the first step (a 1.5 t granite sphere
 * 5 mm deep in an STL slope: 10 kJ created). Touching is allowed. The planes are one-sided but
 * act on a centre less than a radius behind them too, so that counts as inside. */
#define DEM_START_WALL_TOLERANCE 1e-6   /* of the radius */

static int check_wall_overlaps(const dem_sim *s, nc_error *err)
{
    const char *source = s->model.source[0] ? s->model.source : "dem";
    for (size_t i = 0; i < s->model.sph.n; i++) {
        const double *p = s->model.sph.pos + 3 * i, r = s->model.sph.radius[i];
        const double limit = r * (1.0 - DEM_START_WALL_TOLERANCE);
        for (size_t w = 0; w < s->model.n_planes; w++) {
            const dem_plane *pl = &s->model.planes[w];
            double d = 0.0;
            for (int k = 0; k < 3; k++) d += (p[k] - pl->point[k]) * pl->normal[k];
            if (fabs(d) < limit)
                return nc_error_set(err, 1, "%s: particle %d starts %.3g m inside planes[%zu] (its "
                                    "centre %.3g m %s the plane, radius %.3g m): place it on "
                                    "the side the normal points to, touching at most",
                                    source, s->model.sph.id[i], r - d, w, fabs(d),
                                    d >= 0.0 ? "in front of" : "behind", r);
        }
        for (size_t m = 0; m < s->model.n_meshes; m++) {
            const dem_mesh *mesh = &s->model.meshes[m];
            const double q[3] = {p[0] - mesh->offset[0], p[1] - mesh->offset[1],
                                 p[2] - mesh->offset[2]};
            const int32_t *items;
            size_t count = mesh->grid ? dem_item_grid_query(mesh->grid, q, &items) : 0;
            double d2 = INFINITY;
            for (size_t c = 0; c < count; c++) {
                const int32_t *v = mesh->tri + 3 * (size_t)items[c];
                double closest[3];
                dem_tri_feature which;
                d2 = fmin(d2, dem_closest_on_triangle(q, mesh->vertices + 3 * (size_t)v[0],
                                                      mesh->vertices + 3 * (size_t)v[1],
                                                      mesh->vertices + 3 * (size_t)v[2],
                                                      closest, &which));
            }
            if (d2 < limit * limit)
                return nc_error_set(err, 1, "%s: particle %d starts %.3g m inside meshes[%zu] %s "
                                    "(its surface %.3g m from the centre, radius %.3g m): place "
                                    "it outside the mesh, touching at most",
                                    source, s->model.sph.id[i], r - sqrt(d2), m, mesh->path,
                                    sqrt(d2), r);
        }
    }
    return 0;
}

int dem_sim_prepare(dem_sim *s, nc_error *err)
{
    if (s->model.n_materials == 0) return nc_error_set(err, 1, "%s: no materials", s->model.source);
    /* arrays exist even without particles (memcpy/memset never see NULL) */
    if (dem_model_reserve_spheres(&s->model, 1, err) || dem_model_reserve_bodies(&s->model, 1, err)) return -1;
    const dem_contact_law *law = dem_contact_law_of(s->model.prm.law);
    if (law->check(&s->model.prm, s->model.source, err)) return -1;
    for (size_t k = 0; k < s->model.n_materials; k++) {
        dem_material *m = &s->model.materials[k];
        m->shear_modulus_pa = m->youngs_modulus_pa / (2.0 * (1.0 + m->poisson_ratio));
        m->zeta = s->model.prm.damping == DEM_DAMPING_A7 ? dem_zeta_a7(m->restitution)
                                                   : dem_zeta_fit(m->restitution);
        m->hunt_crossley = dem_hunt_crossley_factor(m->restitution);
        m->pair_e_star = dem_effective_modulus(m->youngs_modulus_pa, m->poisson_ratio,
                                               m->youngs_modulus_pa, m->poisson_ratio);
        m->pair_g_star = dem_effective_shear(m->shear_modulus_pa, m->poisson_ratio,
                                             m->shear_modulus_pa, m->poisson_ratio);
        m->pair_kt_kn_root = law->kt_kn_root(&s->model.prm, m->pair_e_star, m->pair_g_star);
    }
    dem_net *net = &s->model.net;
    if (net->youngs_modulus_pa > 0.0)
        net->shear_modulus_pa = net->youngs_modulus_pa / (2.0 * (1.0 + net->poisson_ratio));
    if (net->restitution >= 0.0) {
        net->zeta = s->model.prm.damping == DEM_DAMPING_A7 ? dem_zeta_a7(net->restitution)
                                                     : dem_zeta_fit(net->restitution);
        net->hunt_crossley = dem_hunt_crossley_factor(net->restitution);
    }
    s->model.r_max = 0.0;
    s->model.r_min = INFINITY;
    for (size_t i = 0; i < s->model.sph.n; i++) {
        if (s->model.sph.radius[i] > s->model.r_max) s->model.r_max = s->model.sph.radius[i];
        if (s->model.sph.radius[i] < s->model.r_min) s->model.r_min = s->model.sph.radius[i];
    }
    if (s->model.sph.n == 0) s->model.r_min = s->model.r_max = 1.0;
    if (net->near_distance_m < 0.0) net->near_distance_m = s->model.r_max;
    if (s->model.n_mass_overrides) {
        int32_t *given = malloc(s->model.bod.n * sizeof *given);
        if (!given) return nc_error_set(err, 1, "dem: out of memory for %zu bodies", s->model.bod.n);
        for (size_t b = 0; b < s->model.bod.n; b++) given[b] = -1;
        for (size_t k = 0; k < s->model.n_mass_overrides; k++)
            given[s->model.mass_overrides[k].body] = (int32_t)k;
        for (size_t b = 0; b < s->model.bod.n; b++)
            body_mass_properties(s, b, given[b] >= 0 ? &s->model.mass_overrides[given[b]] : NULL);
        free(given);
    } else {
        for (size_t b = 0; b < s->model.bod.n; b++) body_mass_properties(s, b, NULL);
    }
    if (check_overlaps(s, err)) return -1;
    dem_update_spheres(s);
    if (check_wall_overlaps(s, err)) return -1;

    if (s->model.prm.dt_auto) {
        double dt = s->model.prm.dt_safety * dem_sim_critical_dt(s);
        if (s->model.sph.n > 0) {
            double vmax = 0.0;
            for (size_t b = 0; b < s->model.bod.n; b++) {
                const double *v = s->model.bod.vel + 3 * b;
                double sp = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                if (sp > vmax) vmax = sp;
            }
            double vref = fmax(1.0, 2.0 * vmax);
            double tc = law->contact_time(s, vref) / 40.0; /* >= 40 steps per impact */
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
    size_t n = s->model.sph.n;
    if (dem_thread_work_alloc(&s->work, nb, n, err) ||
        dem_neighbor_list_alloc(&s->nlist, nb, n, s->model.r_min, err) ||
        dem_contact_state_prepare(&s->contact, &s->model, err) ||
        dem_snapshot_alloc(&s->snap, s->model.bod.n, n, err))
        return -1;
    s->n_walls = s->model.n_planes + s->model.n_meshes + 1;
    s->wall_force = calloc(3 * s->n_walls, sizeof *s->wall_force);
    if (!s->wall_force) return nc_error_set(err, 1, "dem: out of memory for %zu spheres", n);
    s->prepared = 1;
    return 0;
}
