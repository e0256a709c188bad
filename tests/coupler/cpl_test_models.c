/* cpl_test_models — closed-form in-process participants and the monolithic reference. */
#include "cpl_test_models.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double *vec(size_t n) { return calloc(n ? n : 1, sizeof(double)); }

void tm_structure_init(tm_structure *s, size_t n_nodes, double m, double k, double k_link)
{
    memset(s, 0, sizeof *s);
    size_t nd = 3 * n_nodes;
    s->nd = nd;
    s->m = vec(nd);
    s->K = vec(nd * nd);
    s->u0 = vec(nd); s->v0 = vec(nd); s->u = vec(nd); s->v = vec(nd);
    s->fail_step = -1;
    s->fail.dt_above_s = INFINITY;
    for (size_t i = 0; i < nd; i++) {
        s->m[i] = m * (1.0 + 0.1 * (double)(i / 3));     /* nodes differ a little */
        s->K[i * nd + i] = k;
    }
    /* springs k_link between neighbouring nodes, same component */
    for (size_t a = 0; a + 1 < n_nodes; a++)
        for (size_t c = 0; c < 3; c++) {
            size_t i = 3 * a + c, j = 3 * (a + 1) + c;
            s->K[i * nd + i] += k_link;
            s->K[j * nd + j] += k_link;
            s->K[i * nd + j] -= k_link;
            s->K[j * nd + i] -= k_link;
        }
}

void tm_structure_free(tm_structure *s)
{
    free(s->m); free(s->K); free(s->u0); free(s->v0); free(s->u); free(s->v);
    memset(s, 0, sizeof *s);
}

void tm_particles_init(tm_particles *p, size_t n_nodes, double mp, double kc, double g)
{
    memset(p, 0, sizeof *p);
    size_t nd = 3 * n_nodes;
    p->nd = nd;
    p->mp = vec(nd); p->kc = vec(nd); p->g = vec(nd);
    p->x0 = vec(nd); p->y0 = vec(nd); p->x = vec(nd); p->y = vec(nd);
    p->w0 = vec(nd); p->w = vec(nd);
    p->fail_step = -1;
    p->fail.dt_above_s = INFINITY;
    p->stiff_factor = 1.0;
    for (size_t i = 0; i < nd; i++) {
        p->mp[i] = mp * (1.0 + 0.2 * (double)(i % 3));
        p->kc[i] = kc * (1.0 + 0.05 * (double)i);
        p->g[i] = (i % 3 == 2) ? g : 0.0;
    }
}

void tm_particles_free(tm_particles *p)
{
    free(p->mp); free(p->kc); free(p->g); free(p->x0); free(p->y0); free(p->x); free(p->y);
    free(p->w0); free(p->w);
    memset(p, 0, sizeof *p);
}

int tm_solve_dense(double *A, double *b, size_t n)
{
    for (size_t c = 0; c < n; c++) {
        size_t piv = c;
        for (size_t r = c + 1; r < n; r++)
            if (fabs(A[r * n + c]) > fabs(A[piv * n + c])) piv = r;
        if (A[piv * n + c] == 0.0) return -1;
        if (piv != c) {
            for (size_t j = 0; j < n; j++) {
                double t = A[c * n + j]; A[c * n + j] = A[piv * n + j]; A[piv * n + j] = t;
            }
            double t = b[c]; b[c] = b[piv]; b[piv] = t;
        }
        for (size_t r = c + 1; r < n; r++) {
            double f = A[r * n + c] / A[c * n + c];
            for (size_t j = c; j < n; j++) A[r * n + j] -= f * A[c * n + j];
            b[r] -= f * b[c];
        }
    }
    for (size_t r = n; r-- > 0;) {
        double s = b[r];
        for (size_t j = r + 1; j < n; j++) s -= A[r * n + j] * b[j];
        b[r] = s / A[r * n + r];
    }
    return 0;
}

int tm_overlaps(double t, double dt, double from, double until)
{
    return t < until - 1e-12 && t + dt > from + 1e-12;
}

/* A retryable failure when the step overlaps the window with too large a Δt. */
static int window_fails(tm_fail_window *w, const cpl_call *call, const char *who, nc_error *err)
{
    if (!(call->dt_s > w->dt_above_s * (1.0 + 1e-12)) ||
        !tm_overlaps(call->time_s, call->dt_s, w->from_s, w->until_s))
        return 0;
    w->failures++;
    return nc_error_set(err, CPL_ERR_STEP_FAILED, "%s: step too large (test: dt %g > %g)", who,
                        call->dt_s, w->dt_above_s);
}

/* ---- structure participant ----------------------------------------------------------- */

static int s_begin(void *ctx, const cpl_call *call, nc_error *err)
{
    (void)call; (void)err;
    tm_structure *s = ctx;
    s->begins++;
    s->open = 1;
    memcpy(s->u, s->u0, s->nd * sizeof(double));
    memcpy(s->v, s->v0, s->nd * sizeof(double));
    return 0;
}

static void structure_solve(tm_structure *s, const double *F, double dt)
{
    size_t nd = s->nd;
    double *A = vec(nd * nd), *b = vec(nd);
    for (size_t i = 0; i < nd; i++) {
        for (size_t j = 0; j < nd; j++) A[i * nd + j] = dt * dt * s->K[i * nd + j];
        A[i * nd + i] += s->m[i];
        b[i] = s->m[i] * (s->u0[i] + dt * s->v0[i]) + dt * dt * F[i];
    }
    tm_solve_dense(A, b, nd);
    for (size_t i = 0; i < nd; i++) {
        s->u[i] = b[i];
        s->v[i] = (b[i] - s->u0[i]) / dt;
    }
    free(A);
    free(b);
}

/* The exact energies of the structure's backward-Euler step (see the header). */
static void structure_energy(const tm_structure *s, const double *F, cpl_energy_report *e)
{
    size_t nd = s->nd;
    double T = 0, U = 0, W = 0, D = 0;
    for (size_t i = 0; i < nd; i++) {
        double du = s->u[i] - s->u0[i], dv = s->v[i] - s->v0[i];
        T += 0.5 * s->m[i] * s->v[i] * s->v[i];
        W += F[i] * du;
        D += 0.5 * s->m[i] * dv * dv;
        for (size_t j = 0; j < nd; j++) {
            U += 0.5 * s->u[i] * s->K[i * nd + j] * s->u[j];
            D += 0.5 * du * s->K[i * nd + j] * (s->u[j] - s->u0[j]);
        }
    }
    *e = (cpl_energy_report){1, T, U, 0.0, W, 0.0, D, NAN};
}

static int s_solve(void *ctx, const cpl_call *call, const double *in0, const double *in1,
                   double *out0, double *out1, cpl_solve_info *info, nc_error *err)
{
    (void)in1;
    tm_structure *s = ctx;
    if (!s->open) return nc_error_set(err, 1, "refused: no step begun (test)");
    if (call->step == s->fail_step && call->iteration == s->fail_iteration)
        return nc_error_set(err, 1, "Newton did not converge in 20 iterations (test)");
    if (window_fails(&s->fail, call, "fem", err)) return -1;
    s->solves++;
    if (call->dt_s > s->dt_seen_max) s->dt_seen_max = call->dt_s;
    structure_solve(s, in0, call->dt_s);   /* restores the start state implicitly */
    structure_energy(s, in0, &info->energy);
    memcpy(out0, s->u, s->nd * sizeof(double));
    memcpy(out1, s->v, s->nd * sizeof(double));
    return 0;
}

static int s_accept(void *ctx, const cpl_call *call, nc_error *err)
{
    (void)call; (void)err;
    tm_structure *s = ctx;
    if (!s->open) return nc_error_set(err, 1, "refused: no step begun (test)");
    s->open = 0;
    s->accepts++;
    memcpy(s->u0, s->u, s->nd * sizeof(double));
    memcpy(s->v0, s->v, s->nd * sizeof(double));
    return 0;
}

/* ---- checkpoint files: raw doubles, written and read in one order ---------------------- */

static int state_file(const char *dir, const char *role, const char *name, int write,
                      double **parts, size_t n_parts, size_t nd, long *failures, nc_error *err)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s_%s.bin", dir, role, name);
    FILE *f = fopen(path, write ? "wb" : "rb");
    if (!f) return nc_error_set(err, 1, "%s: cannot open (test checkpoint)", path);
    int ok = 1;
    for (size_t k = 0; k < n_parts && ok; k++)
        ok = (write ? fwrite(parts[k], sizeof(double), nd, f) : fread(parts[k], sizeof(double), nd, f)) == nd;
    ok = ok && (write ? fwrite(failures, sizeof *failures, 1, f) : fread(failures, sizeof *failures, 1, f)) == 1;
    ok = (fclose(f) == 0) && ok;
    return ok ? 0 : nc_error_set(err, 1, "%s: short %s (test checkpoint)", path, write ? "write" : "read");
}

static int s_checkpoint(void *ctx, const cpl_call *call, const char *name, nc_error *err)
{
    (void)call;
    tm_structure *s = ctx;
    if (s->open) return nc_error_set(err, 1, "checkpoint refused: inside a begun step (test)");
    double *parts[2] = {s->u0, s->v0};
    s->checkpoints++;
    return state_file(s->checkpoint_dir, "fem", name, 1, parts, 2, s->nd, &s->fail.failures, err);
}

static int s_resume(void *ctx, const cpl_call *call, const char *name, nc_error *err)
{
    (void)call;
    tm_structure *s = ctx;
    double *parts[2] = {s->u0, s->v0};
    s->resumes++;
    return state_file(s->checkpoint_dir, "fem", name, 0, parts, 2, s->nd, &s->fail.failures, err);
}

cpl_participant tm_structure_participant(tm_structure *s)
{
    cpl_participant p = {"fem", s, s_begin, s_solve, s_accept, 0,
                         s->checkpoint_dir ? s_checkpoint : NULL,
                         s->checkpoint_dir ? s_resume : NULL, NULL, NULL, 0};
    return p;
}

/* ---- particle participant ------------------------------------------------------------ */

static int p_begin(void *ctx, const cpl_call *call, nc_error *err)
{
    (void)call; (void)err;
    tm_particles *p = ctx;
    memcpy(p->x, p->x0, p->nd * sizeof(double));
    memcpy(p->y, p->y0, p->nd * sizeof(double));
    return 0;
}

static int p_solve(void *ctx, const cpl_call *call, const double *in0, const double *in1,
                   double *out0, double *out1, cpl_solve_info *info, nc_error *err)
{
    (void)in1; (void)out1;
    tm_particles *p = ctx;
    if (call->step == p->fail_step && call->iteration == p->fail_iteration)
        return nc_error_set(err, 1, "particle solver failed (test)");
    if (window_fails(&p->fail, call, "dem", err)) return -1;
    p->solves++;
    double dt = call->dt_s;
    double f = tm_overlaps(call->time_s, dt, p->stiff_from_s, p->stiff_until_s)
                   ? p->stiff_factor : 1.0;
    cpl_energy_report *e = &info->energy;
    *e = (cpl_energy_report){1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, NAN};
    for (size_t i = 0; i < p->nd; i++) {
        double kc = f * p->kc[i];
        double x1 = (p->mp[i] * (p->x0[i] + dt * p->y0[i]) +
                     dt * dt * (kc * in0[i] + p->mp[i] * p->g[i])) /
                    (p->mp[i] + dt * dt * kc);
        p->y[i] = (x1 - p->x0[i]) / dt;
        p->x[i] = x1;
        p->w[i] = in0[i];
        out0[i] = kc * (x1 - in0[i]);
        double s1 = x1 - in0[i], ds = s1 - (p->x0[i] - p->w0[i]), dy = p->y[i] - p->y0[i];
        e->kinetic_j += 0.5 * p->mp[i] * p->y[i] * p->y[i];
        e->elastic_j += 0.5 * kc * s1 * s1;
        e->potential_j -= p->mp[i] * p->g[i] * x1;
        e->interface_work_j -= kc * s1 * (in0[i] - p->w0[i]);
        e->dissipated_j += 0.5 * p->mp[i] * dy * dy + 0.5 * kc * ds * ds;
    }
    info->near_interface = call->time_s + call->dt_s < p->far_until_s ? 0 : 1;
    info->contacts = 1;
    return 0;
}

static int p_accept(void *ctx, const cpl_call *call, nc_error *err)
{
    (void)call; (void)err;
    tm_particles *p = ctx;
    memcpy(p->x0, p->x, p->nd * sizeof(double));
    memcpy(p->y0, p->y, p->nd * sizeof(double));
    memcpy(p->w0, p->w, p->nd * sizeof(double));
    return 0;
}

static int p_checkpoint(void *ctx, const cpl_call *call, const char *name, nc_error *err)
{
    (void)call;
    tm_particles *p = ctx;
    double *parts[3] = {p->x0, p->y0, p->w0};
    p->checkpoints++;
    return state_file(p->checkpoint_dir, "dem", name, 1, parts, 3, p->nd, &p->fail.failures, err);
}

static int p_resume(void *ctx, const cpl_call *call, const char *name, nc_error *err)
{
    (void)call;
    tm_particles *p = ctx;
    double *parts[3] = {p->x0, p->y0, p->w0};
    p->resumes++;
    return state_file(p->checkpoint_dir, "dem", name, 0, parts, 3, p->nd, &p->fail.failures, err);
}

cpl_participant tm_particles_participant(tm_particles *p)
{
    cpl_participant q = {"dem", p, p_begin, p_solve, p_accept, 0,
                         p->checkpoint_dir ? p_checkpoint : NULL,
                         p->checkpoint_dir ? p_resume : NULL, NULL, NULL, 0};
    return q;
}

void tm_monolithic_step(tm_structure *s, tm_particles *p, double t, double dt)
{
    size_t nd = s->nd, n = 2 * nd;
    double *A = vec(n * n), *b = vec(n);
    double f = tm_overlaps(t, dt, p->stiff_from_s, p->stiff_until_s) ? p->stiff_factor : 1.0;
    for (size_t i = 0; i < nd; i++) {
        double kc = f * p->kc[i];
        /* structure rows: (M + dt² K) u − dt² kc (x − u) = M (u0 + dt v0) */
        for (size_t j = 0; j < nd; j++) A[i * n + j] = dt * dt * s->K[i * nd + j];
        A[i * n + i] += s->m[i] + dt * dt * kc;
        A[i * n + nd + i] = -dt * dt * kc;
        b[i] = s->m[i] * (s->u0[i] + dt * s->v0[i]);
        /* particle rows: (mp + dt² kc) x − dt² kc u = mp (x0 + dt y0) + dt² mp g */
        size_t r = nd + i;
        A[r * n + nd + i] = p->mp[i] + dt * dt * kc;
        A[r * n + i] = -dt * dt * kc;
        b[r] = p->mp[i] * (p->x0[i] + dt * p->y0[i]) + dt * dt * p->mp[i] * p->g[i];
    }
    tm_solve_dense(A, b, n);
    for (size_t i = 0; i < nd; i++) {
        s->v0[i] = (b[i] - s->u0[i]) / dt;
        s->u0[i] = b[i];
        p->y0[i] = (b[nd + i] - p->x0[i]) / dt;
        p->x0[i] = b[nd + i];
    }
    free(A);
    free(b);
}

/* ---- recorder ------------------------------------------------------------------------ */

static int r_iteration(void *ctx, const cpl_iteration_record *rec, nc_error *err)
{
    (void)err;
    tm_recorder *r = ctx;
    r->total_iterations++;
    if (rec->step == 0 && rec->iteration >= 1 && rec->iteration <= 512)
        r->step0_residual[rec->iteration - 1] = rec->residual;
    r->last_iteration_count = rec->iteration;
    return 0;
}

static int r_step(void *ctx, const cpl_step_record *rec, nc_error *err)
{
    (void)err;
    tm_recorder *r = ctx;
    if (r->steps < 4096) {
        r->iterations[r->steps] = rec->iterations;
        r->residual[r->steps] = rec->residual;
        r->converged[r->steps] = rec->converged;
        r->time[r->steps] = rec->time_s;
        r->force_z[r->steps] = rec->contact_force[2];
        r->dt[r->steps] = rec->dt_s;
        r->rejected[r->steps] = rec->rejected;
    }
    r->steps++;
    return 0;
}

static int r_reject(void *ctx, const cpl_reject_record *rec, nc_error *err)
{
    (void)err;
    tm_recorder *r = ctx;
    if (r->rejections < 64) {
        r->reject[r->rejections] = *rec;
        r->reject[r->rejections].message = "";
    }
    r->rejections++;
    return 0;
}

cpl_observer tm_recorder_observer(tm_recorder *r)
{
    memset(r, 0, sizeof *r);
    cpl_observer o = {r, r_iteration, r_step, r_reject, NULL};
    return o;
}

cpl_loop_settings tm_loop_settings(cpl_scheme scheme, double dt, double end)
{
    cpl_loop_settings s;
    cpl_loop_settings_default(&s);
    s.scheme = scheme;
    s.dt_s = dt;
    s.end_time_s = end;
    s.tol_abs = 1e-10;
    s.max_iterations = 200;
    return s;
}

const tm_problem TM_MILD = {1, 1.0, 100.0, 0.0, 1.0, 1000.0, -9.81};
const tm_problem TM_HARD = {2, 0.1, 100.0, 50.0, 10.0, 1e5, -9.81};
