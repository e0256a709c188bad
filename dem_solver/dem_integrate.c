/* dem_integrate — symplectic Euler time integration of translation and rotation. */
#include "dem_integrate.h"

#include <math.h>
#include <string.h>

void dem_quat_to_matrix(const double q[4], double r[9])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    r[0] = 1 - 2 * (y * y + z * z); r[1] = 2 * (x * y - w * z);     r[2] = 2 * (x * z + w * y);
    r[3] = 2 * (x * y + w * z);     r[4] = 1 - 2 * (x * x + z * z); r[5] = 2 * (y * z - w * x);
    r[6] = 2 * (x * z - w * y);     r[7] = 2 * (y * z + w * x);     r[8] = 1 - 2 * (x * x + y * y);
}

void dem_quat_rotate(const double q[4], const double v[3], double out[3])
{
    double r[9];
    dem_quat_to_matrix(q, r);
    for (int a = 0; a < 3; a++) out[a] = r[3 * a] * v[0] + r[3 * a + 1] * v[1] + r[3 * a + 2] * v[2];
}

void dem_cluster_omega(const double q[4], const double inv_inertia_body[9], const double L[3],
                       double omega[3])
{
    double r[9], lb[3], wb[3];
    dem_quat_to_matrix(q, r);
    for (int a = 0; a < 3; a++) lb[a] = r[a] * L[0] + r[3 + a] * L[1] + r[6 + a] * L[2]; /* Rᵀ L */
    for (int a = 0; a < 3; a++)
        wb[a] = inv_inertia_body[3 * a] * lb[0] + inv_inertia_body[3 * a + 1] * lb[1] +
                inv_inertia_body[3 * a + 2] * lb[2];
    for (int a = 0; a < 3; a++) omega[a] = r[3 * a] * wb[0] + r[3 * a + 1] * wb[1] + r[3 * a + 2] * wb[2];
}

/* Rigid-body kinematics of the spheres of body k. */
/* One explicit step of the orientation, q̇ = ½ (0, ω) ⊗ q, then renormalised. */
static void quat_advance(double q[4], const double w[3], double h)
{
    double dq[4] = {-w[0] * q[1] - w[1] * q[2] - w[2] * q[3],
                    w[0] * q[0] + w[1] * q[3] - w[2] * q[2],
                    -w[0] * q[3] + w[1] * q[0] + w[2] * q[1],
                    w[0] * q[2] - w[1] * q[1] + w[2] * q[0]};
    double norm = 0.0;
    for (int d = 0; d < 4; d++) {
        q[d] += 0.5 * h * dq[d];
        norm += q[d] * q[d];
    }
    norm = sqrt(norm);
    for (int d = 0; d < 4; d++) q[d] /= norm;
}

static inline void place_spheres(dem_sim *s, long k)
{
    const dem_bodies *b = &s->model.bod;
    int32_t first = b->first_sphere[k], count = b->n_spheres[k];
    const double *xb = b->pos + 3 * k, *vb = b->vel + 3 * k, *w = b->omega + 3 * k;
    if (!b->is_cluster[k]) {
        double *x = s->model.sph.pos + 3 * (size_t)first, *v = s->model.sph.vel + 3 * (size_t)first;
        x[0] = xb[0];
        x[1] = xb[1];
        x[2] = xb[2];
        v[0] = vb[0];
        v[1] = vb[1];
        v[2] = vb[2];
        return;
    }
    double r[9];
    dem_quat_to_matrix(b->quat + 4 * k, r);
    for (int32_t q = first; q < first + count; q++) {
        const double *o = s->model.sph.offset + 3 * (size_t)q;
        double d[3];
        for (int a = 0; a < 3; a++) d[a] = r[3 * a] * o[0] + r[3 * a + 1] * o[1] + r[3 * a + 2] * o[2];
        double *x = s->model.sph.pos + 3 * (size_t)q, *v = s->model.sph.vel + 3 * (size_t)q;
        x[0] = xb[0] + d[0];
        x[1] = xb[1] + d[1];
        x[2] = xb[2] + d[2];
        v[0] = vb[0] + w[1] * d[2] - w[2] * d[1];
        v[1] = vb[1] + w[2] * d[0] - w[0] * d[2];
        v[2] = vb[2] + w[0] * d[1] - w[1] * d[0];
    }
}

/* Moves body k over dt (eq. (16), (17)); returns the larger of worst and the squared
 * displacement of its spheres since the neighbour list was built (NaN when one is NaN).
 * Inlined into both loops below: as a call it costs 4 % more instructions in the settle
 * benchmark (lackey, dem_bench 5000 100 --threads 1: 261.8 against 249.7 million). */
static inline __attribute__((always_inline)) double integrate_body(dem_sim *s, long k, double dt, double worst)
{
    dem_bodies *b = &s->model.bod;
    const double *g = s->model.prm.gravity;
    int32_t first = b->first_sphere[k], count = b->n_spheres[k];
    double *x = b->pos + 3 * k;
    if (!b->is_cluster[k]) { /* free sphere: the same arithmetic, fewer memory streams */
        size_t q = (size_t)first;
        const double *f = s->model.sph.force + 3 * q, *ts = s->model.sph.torque + 3 * q;
        double *xs = s->model.sph.pos + 3 * q, *vs = s->model.sph.vel + 3 * q;
        double r0 = xs[0] - x[0], r1 = xs[1] - x[1], r2 = xs[2] - x[2];
        double F0 = 0.0 + f[0], F1 = 0.0 + f[1], F2 = 0.0 + f[2];
        double T0 = 0.0 + (ts[0] + r1 * f[2] - r2 * f[1]);
        double T1 = 0.0 + (ts[1] + r2 * f[0] - r0 * f[2]);
        double T2 = 0.0 + (ts[2] + r0 * f[1] - r1 * f[0]);
        double *bf = b->force + 3 * k, *bt = b->torque + 3 * k;
        bf[0] = F0;
        bf[1] = F1;
        bf[2] = F2;
        bt[0] = T0;
        bt[1] = T1;
        bt[2] = T2;
        double *v = b->vel + 3 * k, *w = b->omega + 3 * k;
        double im = b->inv_mass[k], ii = b->inv_inertia_iso[k];
        v[0] += dt * (F0 * im + g[0]); /* eq. (16), velocity first */
        v[1] += dt * (F1 * im + g[1]);
        v[2] += dt * (F2 * im + g[2]);
        double x0 = x[0] + dt * v[0], x1 = x[1] + dt * v[1], x2 = x[2] + dt * v[2];
        x[0] = xs[0] = x0;
        x[1] = xs[1] = x1;
        x[2] = xs[2] = x2;
        w[0] += dt * T0 * ii; /* eq. (17) */
        w[1] += dt * T1 * ii;
        w[2] += dt * T2 * ii;
        vs[0] = v[0];
        vs[1] = v[1];
        vs[2] = v[2];
        const double *p0 = s->nlist.pos_at_build + 3 * q;
        double d0 = x0 - p0[0], d1 = x1 - p0[1], d2c = x2 - p0[2];
        double d2 = d0 * d0 + d1 * d1 + d2c * d2c;
        if (!(d2 <= worst)) worst = d2; /* NaN propagates and forces a rebuild */
        return worst;
    }
    /* spheres -> body, in sphere order (deterministic) */
    double F[3] = {0, 0, 0}, T[3] = {0, 0, 0};
    for (int32_t q = first; q < first + count; q++) {
        const double *f = s->model.sph.force + 3 * (size_t)q, *xs = s->model.sph.pos + 3 * (size_t)q;
        const double *ts = s->model.sph.torque + 3 * (size_t)q;
        double r[3] = {xs[0] - x[0], xs[1] - x[1], xs[2] - x[2]};
        F[0] += f[0];
        F[1] += f[1];
        F[2] += f[2];
        T[0] += ts[0] + r[1] * f[2] - r[2] * f[1];
        T[1] += ts[1] + r[2] * f[0] - r[0] * f[2];
        T[2] += ts[2] + r[0] * f[1] - r[1] * f[0];
    }
    memcpy(b->force + 3 * k, F, sizeof F);
    memcpy(b->torque + 3 * k, T, sizeof T);

    double *v = b->vel + 3 * k, *w = b->omega + 3 * k;
    double im = b->inv_mass[k];
    for (int d = 0; d < 3; d++) {
        v[d] += dt * (F[d] * im + g[d]); /* eq. (16), velocity first */
        x[d] += dt * v[d];
    }
    if (!b->is_cluster[k]) {
        double ii = b->inv_inertia_body[9 * k]; /* isotropic sphere */
        for (int d = 0; d < 3; d++) w[d] += dt * T[d] * ii; /* eq. (17) */
    } else {
        double *L = b->angmom + 3 * k, *q = b->quat + 4 * k;
        const double *ib = b->inv_inertia_body + 9 * k;
        for (int d = 0; d < 3; d++) L[d] += dt * T[d];
        dem_cluster_omega(q, ib, L, w);
        quat_advance(q, w, dt);
        dem_cluster_omega(q, ib, L, w);
    }
    place_spheres(s, k);
    for (int32_t q = first; q < first + count; q++) {
        const double *p = s->model.sph.pos + 3 * (size_t)q, *p0 = s->nlist.pos_at_build + 3 * (size_t)q;
        double d[3] = {p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]};
        double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if (!(d2 <= worst)) worst = d2; /* NaN propagates and forces a rebuild */
    }
    return worst;
}

void dem_integrate_bodies(dem_sim *s, double dt)
{
    long n = (long)s->model.bod.n;
    double worst = s->nlist.max_disp2;
    if (n >= DEM_PARALLEL_MIN) {
#pragma omp parallel for schedule(static) reduction(max : worst) num_threads(s->work.n_buffers)
        for (long k = 0; k < n; k++) worst = integrate_body(s, k, dt, worst);
    } else {
        for (long k = 0; k < n; k++) worst = integrate_body(s, k, dt, worst);
    }
    s->nlist.max_disp2 = worst;
}

void dem_free_flight(dem_sim *s, double dt, long rot_substeps)
{
    dem_bodies *b = &s->model.bod;
    const double *g = s->model.prm.gravity;
    double h = dt / (double)(rot_substeps > 0 ? rot_substeps : 1);
    for (size_t k = 0; k < b->n; k++) {
        double *x = b->pos + 3 * k, *v = b->vel + 3 * k, *w = b->omega + 3 * k;
        for (int d = 0; d < 3; d++) {
            x[d] += v[d] * dt + 0.5 * g[d] * dt * dt;
            v[d] += g[d] * dt;
        }
        if (!b->is_cluster[k]) continue;
        double *q = b->quat + 4 * k;
        const double *L = b->angmom + 3 * k, *ib = b->inv_inertia_body + 9 * k;
        for (long r = 0; r < rot_substeps; r++) {
            dem_cluster_omega(q, ib, L, w);
            quat_advance(q, w, h);
        }
        dem_cluster_omega(q, ib, L, w);
    }
    dem_update_spheres(s);
    s->nlist.rebuild = 1;
}

void dem_update_spheres(dem_sim *s)
{
    long n = (long)s->model.bod.n;
    if (n >= DEM_PARALLEL_MIN) {
#pragma omp parallel for schedule(static) num_threads(s->work.n_buffers)
        for (long k = 0; k < n; k++) place_spheres(s, k);
    } else {
        for (long k = 0; k < n; k++) place_spheres(s, k);
    }
}
