/* test_linearised_contact — the interface linearisation of the coupling force
 * (fem_analysis_set_linearisation): F(u, v) = F^k - K (u - u^k) - C (v - v^k) solved
 * implicitly. Checks: a one-free-node model against an independent integration of the same
 * system written out here (Newmark, generalized-alpha, Bossak; end-of-step and step-constant
 * coupling load, the latter with the linearised force over the whole step); Newton with the
 * consistent tangent needs no more iterations than without the linearisation (+1) and the
 * solution satisfies F at the final iterate; K = C = 0 is bit-identical to the plain
 * coupling force; the step tangent with edge blocks (a, b) against finite differences of
 * the residual; save/restore bit-identity; an unsymmetric K; statics; the rounding floor
 * under a stiff K; rejection of blocks the fixed pattern cannot hold. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../../fem_solver/fem_analysis.h"
#include "../../fem_solver/fem_element_cable.h"
#include "fem_test_util.h"

/* ---- one free node: the middle node of a prestressed two-element cable --------------- */

/* L = 1 m, E A = 1e5 N, tension 100 N, rho A = 0.1 kg/m: the free node has a mass of
 * 2 m11 = 1/30 kg (consistent mass; m12 couples it only to the fixed ends) and stiffnesses of
 * 400 N/m across and 4e5 N/m along the cable. The contact (k = 1e4 N/m, c = 5 N s/m) dominates
 * across the cable, as a rock's contact does on a light cable node. */
#define LN_K 1e4
#define LN_C 5.0
#define LN_DT 1e-4
#define LN_STEPS 60

static void line_model(fem_model *m, fem_integrator integ, int step_constant)
{
    fem_test_line(m, 2, 1.0, 1e9, 1e-4, 1000.0, 1e6, FEM_CABLE, 1);
    m->settings.type = FEM_DYNAMIC;
    m->settings.integrator = integ;
    m->settings.rho_inf = 0.8;
    m->settings.alpha_b = -0.1;
    m->settings.dt_s = LN_DT;
    m->settings.coupling_load_constant = step_constant;
    /* the residual carries 100 N element forces (round-off ~1e-14 N): 1e-11 N is reachable
     * and moves the node by ~1e-15 m, 1e-11 of the amplitude */
    m->settings.residual_tol_n = 1e-11;
    m->settings.relative_tol = 1e-15;
    m->settings.displacement_tol_m = 1e-13;
    m->tau_per_s = 2.0;
    nc_error err;
    assert_int_equal(fem_model_finalize(m, &err), 0);
}

static const double LN_F0[3] = {1.0, -2.0, -5.0};      /* F^k (N) */
static const double LN_U0[3] = {1e-5, 2e-4, -3e-4};    /* u^k (m) */
static const double LN_V0[3] = {0.0, 0.05, -0.2};      /* v^k (m/s) */
static const double LN_VINIT[3] = {0.01, -0.1, 0.3};   /* initial velocity (m/s) */

/* internal force on the free node and its tangent, from both elements */
static void line_internal(const fem_model *m, const double u[3], double f[3], double Kt[9])
{
    double d0[3], d1[3], f0[3], f1[3], K0[9], K1[9];
    int slack;
    for (int c = 0; c < 3; c++) {
        d0[c] = m->X[3 + c] + u[c] - m->X[c];
        d1[c] = m->X[6 + c] - m->X[3 + c] - u[c];
    }
    fem_cable_response(d0, m->L0[0], m->EA[0], m->AS[0], m->is_cable[0], f0, K0, &slack);
    fem_cable_response(d1, m->L0[1], m->EA[1], m->AS[1], m->is_cable[1], f1, K1, &slack);
    for (int c = 0; c < 3; c++) f[c] = f0[c] - f1[c];
    for (int e = 0; e < 9; e++) Kt[e] = K0[e] + K1[e];
}

static void solve3(const double A[9], const double b[3], double x[3])
{
    double det = A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
                 A[2] * (A[3] * A[7] - A[4] * A[6]);
    for (int c = 0; c < 3; c++) {
        double M[9];
        memcpy(M, A, sizeof M);
        for (int r = 0; r < 3; r++) M[3 * r + c] = b[r];
        x[c] = (M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
                M[2] * (M[3] * M[7] - M[4] * M[6])) / det;
    }
}

/* the linearisation's damping: LN_C, or 0 for the step-constant load, whose shift of a_n
 * through C the FEM leaves out (fem_analysis.c: exact for C = 0, what the DEM sends) */
static double line_damping(int step_constant)
{
    return step_constant ? 0.0 : LN_C;
}

/* F(u, v) with damping lc */
static double lin_force(int c, const double u[3], const double v[3], double lc)
{
    return LN_F0[c] - LN_K * (u[c] - LN_U0[c]) - lc * (v[c] - LN_V0[c]);
}

/* The same system stepped independently: the generalized-alpha step equation
 *   F(u1, v1) - M (a_am + tau v_af) - (1 - af) F_int(u1) - af F_int(u0) = 0
 * with the coupling force at the end of the step (as f_coupling acts), Newmark kinematics,
 * and for step_constant the start acceleration shifted by (F(u1) - fc_n)/M: the linearised
 * force acts over the whole step, as a step-constant coupling force does (C = 0 there, so
 * F depends on u1 alone). */
static void hand_run(const fem_model *m, double beta, double gamma, double am, double af,
                     int step_constant, double (*hist)[9])
{
    const double M = 2.0 * m->rhoA[0] * m->L0[0] / 3.0, tau = m->tau_per_s, dt = LN_DT;
    const double lc = line_damping(step_constant);
    double u[3] = {0, 0, 0}, v[3], a[3], f[3], Kt[9], fc[3];
    memcpy(v, LN_VINIT, sizeof v);
    line_internal(m, u, f, Kt);
    for (int c = 0; c < 3; c++) {
        fc[c] = lin_force(c, u, v, lc);
        a[c] = (fc[c] - f[c] - tau * M * v[c]) / M;
    }
    for (int n = 0; n < LN_STEPS; n++) {
        double un[3], vn[3], an[3], fn[3];
        memcpy(un, u, sizeof un);
        memcpy(vn, v, sizeof vn);
        memcpy(an, a, sizeof an);
        line_internal(m, un, fn, Kt);
        const double an_plain[3] = {an[0], an[1], an[2]};
        const double c0 = 1.0 / (beta * dt * dt), c2 = 1.0 / (2.0 * beta) - 1.0;
        /* d a_n / d u1 of the step-constant shift */
        const double dan = step_constant ? -LN_K / M : 0.0;
        for (int it = 0; it < 30; it++) {
            double r[3], J[9], du[3];
            line_internal(m, u, f, Kt);
            for (int c = 0; c < 3; c++) {
                if (step_constant) an[c] = an_plain[c] + (lin_force(c, u, v, lc) - fc[c]) / M;
                a[c] = c0 * (u[c] - un[c] - dt * vn[c]) - c2 * an[c];
                v[c] = vn[c] + dt * ((1.0 - gamma) * an[c] + gamma * a[c]);
                double a_am = (1.0 - am) * a[c] + am * an[c];
                double v_af = (1.0 - af) * v[c] + af * vn[c];
                r[c] = lin_force(c, u, v, lc) - M * (a_am + tau * v_af) - (1.0 - af) * f[c] - af * fn[c];
            }
            /* d a1/du1, d v1/du1 and the Jacobian of r (its minus sign folded in) */
            const double da = c0 - c2 * dan, dv = dt * ((1.0 - gamma) * dan + gamma * da);
            double cm = M * ((1.0 - am) * da + am * dan) + tau * M * (1.0 - af) * dv;
            for (int e = 0; e < 9; e++) J[e] = (1.0 - af) * Kt[e];
            for (int c = 0; c < 3; c++) J[4 * c] += cm + LN_K + lc * dv;
            solve3(J, r, du);
            for (int c = 0; c < 3; c++) u[c] += du[c];
            if (fmax(fabs(du[0]), fmax(fabs(du[1]), fabs(du[2]))) < 1e-17) break;
        }
        for (int c = 0; c < 3; c++) {
            if (step_constant) an[c] = an_plain[c] + (lin_force(c, u, v, lc) - fc[c]) / M;
            a[c] = c0 * (u[c] - un[c] - dt * vn[c]) - c2 * an[c];
            v[c] = vn[c] + dt * ((1.0 - gamma) * an[c] + gamma * a[c]);
            fc[c] = lin_force(c, u, v, lc);
            hist[n][c] = u[c];
            hist[n][3 + c] = v[c];
            hist[n][6 + c] = a[c];
        }
    }
}

/* full-dof vectors of the line model's linearisation at node 1, damping lc */
static void line_set_linearisation(fem_analysis *s, double lc)
{
    double uref[9] = {0}, vref[9] = {0}, K[9] = {0}, C[9] = {0};
    for (int c = 0; c < 3; c++) {
        s->f_coupling[3 + c] = LN_F0[c];
        uref[3 + c] = LN_U0[c];
        vref[3 + c] = LN_V0[c];
        K[4 * c] = LN_K;
        C[4 * c] = lc;
    }
    const int nodes[2] = {1, 1};
    nc_error err;
    if (fem_analysis_set_linearisation(s, uref, vref, 1, nodes, K, C, &err)) fail_msg("%s", err.message);
}

static void run_monolithic(fem_integrator integ, int step_constant)
{
    fem_model m;
    line_model(&m, integ, step_constant);
    fem_analysis s;
    nc_error err;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    const double lc = line_damping(step_constant);
    line_set_linearisation(&s, lc);
    for (int c = 0; c < 3; c++) s.cur.v[3 + c] = LN_VINIT[c];
    assert_int_equal(fem_analysis_initial_acceleration(&s, &err), 0);
    double beta, gamma, am = 0, af = 0;
    if (integ == FEM_GENERALIZED_ALPHA) {
        double r = m.settings.rho_inf;
        am = (2 * r - 1) / (r + 1);
        af = r / (r + 1);
    } else if (integ == FEM_BOSSAK) {
        am = m.settings.alpha_b;
    }
    gamma = integ == FEM_NEWMARK ? m.settings.gamma : 0.5 - am + af;
    beta = integ == FEM_NEWMARK ? m.settings.beta : 0.25 * (1 - am + af) * (1 - am + af);
    double (*hist)[9] = malloc(LN_STEPS * sizeof *hist);
    hand_run(&m, beta, gamma, am, af, step_constant, hist);
    double umax = 0, vmax = 0, amax = 0;
    for (int n = 0; n < LN_STEPS; n++)
        for (int c = 0; c < 3; c++) {
            umax = fmax(umax, fabs(hist[n][c]));
            vmax = fmax(vmax, fabs(hist[n][3 + c]));
            amax = fmax(amax, fabs(hist[n][6 + c]));
        }
    for (int n = 0; n < LN_STEPS; n++) {
        if (fem_analysis_step(&s, LN_DT, &err)) fail_msg("%s", err.message);
        /* both solves converge to ~1e-15 m; 1e-9 of the largest value leaves room for the
         * different operation order (sparse assembly vs. the 3x3 form here) */
        for (int c = 0; c < 3; c++) {
            assert_near(s.cur.u[3 + c], hist[n][c], 1e-9 * umax);
            assert_near(s.cur.v[3 + c], hist[n][3 + c], 1e-9 * vmax);
            assert_near(s.cur.a[3 + c], hist[n][6 + c], 1e-9 * amax);
            /* cur.fc is F at the solution */
            double fc = lin_force(c, s.cur.u + 3, s.cur.v + 3, lc);
            assert_near(s.cur.fc[3 + c], fc, 1e-12 * (fabs(LN_F0[c]) + LN_K * umax + lc * vmax));
        }
    }
    /* the contact matters: the node moved well away from where F^k alone would hold it */
    assert_below(1e-5, umax);
    free(hist);
    fem_analysis_free(&s);
    fem_model_free(&m);
}

static void test_monolithic_newmark(void **state) { (void)state; run_monolithic(FEM_NEWMARK, 0); }
static void test_monolithic_generalized_alpha(void **state) { (void)state; run_monolithic(FEM_GENERALIZED_ALPHA, 0); }
static void test_monolithic_bossak(void **state) { (void)state; run_monolithic(FEM_BOSSAK, 0); }
static void test_monolithic_step_constant(void **state)
{
    (void)state;
    run_monolithic(FEM_NEWMARK, 1);
    run_monolithic(FEM_GENERALIZED_ALPHA, 1);
    run_monolithic(FEM_BOSSAK, 1);
}

/* ---- a prestressed 7 x 7 net (unit square, boundary fixed) --------------------------- */

#define NET_N 7
#define NET_CENTRE 24   /* node (3, 3) */
#define NET_EDGE_B 25   /* node (4, 3): shares an element with the centre */
#define NET_DT 1e-3

static void net_model(fem_model *m, fem_integrator integ, int modified_newton, int step_constant)
{
    fem_element_set set = {"net", 1e9, 1.26e-4, 7850, 1e6, FEM_CABLE, 0.0};
    nc_error err;
    if (!fem_test_net(m, NET_N, &set, &err)) fail_msg("%s", err.message);
    m->settings.type = FEM_DYNAMIC;
    m->settings.integrator = integ;
    m->settings.rho_inf = 0.7;
    m->settings.alpha_b = -0.15;
    m->settings.dt_s = NET_DT;
    m->settings.modified_newton = modified_newton;
    m->settings.coupling_load_constant = step_constant;
    m->tau_per_s = 3.0;
    if (fem_model_finalize(m, &err)) fail_msg("%s", err.message);
}

/* Contact of a sphere on the edge (a, b) at a fraction xi from a along unit normal n:
 * F_a = (1 - xi) F, F_b = xi F with F = -k_n (n . gap) n, so K_pq = k_n w_p w_q n n^T with
 * w = (1 - xi, xi) (C likewise with c_n): the 2 x 2 node-block structure. */
static int edge_blocks(int a, int b, double k_n, double c_n, int *nodes, double *K, double *C)
{
    const double xi = 0.3, nr[3] = {0.2, -0.1, 1.0};
    double len = sqrt(nr[0] * nr[0] + nr[1] * nr[1] + nr[2] * nr[2]), n[3];
    for (int c = 0; c < 3; c++) n[c] = nr[c] / len;
    const int who[2] = {a, b};
    const double w[2] = {1.0 - xi, xi};
    int nb = 0;
    for (int p = 0; p < 2; p++)
        for (int q = 0; q < 2; q++, nb++) {
            nodes[2 * nb] = who[p];
            nodes[2 * nb + 1] = who[q];
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 3; c++) {
                    K[9 * nb + 3 * r + c] = k_n * w[p] * w[q] * n[r] * n[c];
                    C[9 * nb + 3 * r + c] = c_n * w[p] * w[q] * n[r] * n[c];
                }
        }
    return nb;
}

/* F^k on the edge nodes (a downward push) */
static void edge_force(fem_analysis *s, double scale)
{
    memset(s->f_coupling, 0, (size_t)s->ndof * sizeof(double));
    s->f_coupling[3 * NET_CENTRE + 2] = -0.7 * scale;
    s->f_coupling[3 * NET_EDGE_B + 2] = -0.3 * scale;
    s->f_coupling[3 * NET_CENTRE + 0] = 0.05 * scale;
}

static void set_edge_linearisation(fem_analysis *s, double k_n, double c_n, const double *uref,
                                   const double *vref)
{
    int nodes[8];
    double K[36], C[36];
    int nb = edge_blocks(NET_CENTRE, NET_EDGE_B, k_n, c_n, nodes, K, C);
    nc_error err;
    if (fem_analysis_set_linearisation(s, uref, vref, nb, nodes, K, C, &err)) fail_msg("%s", err.message);
}

/* Newton with the consistent tangent: a large push (many iterations, slack-free but strongly
 * nonlinear) with a stiff, damped contact linearised about the start of each step needs at
 * most one iteration more per step than the same push without it; the step's solution
 * satisfies F(u, v) (cur.fc) and solving again with the plain force f_coupling = F(u, v)
 * gives the same step. */
static void run_newton(fem_integrator integ, int modified_newton)
{
    fem_model m;
    net_model(&m, integ, modified_newton, 0);
    fem_analysis plain, lin, check;
    nc_error err;
    assert_int_equal(fem_analysis_init(&plain, &m, &err), 0);
    assert_int_equal(fem_analysis_init(&lin, &m, &err), 0);
    assert_int_equal(fem_analysis_init(&check, &m, &err), 0);
    const double k_n = 2e5, c_n = 200.0;
    int nodes[8];
    double K[36], C[36];
    edge_blocks(NET_CENTRE, NET_EDGE_B, k_n, c_n, nodes, K, C);
    edge_force(&plain, 3000.0);
    edge_force(&lin, 3000.0);
    assert_int_equal(fem_analysis_initial_acceleration(&plain, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(&lin, &err), 0);
    int worse = 0;
    for (int n = 0; n < 12; n++) {
        if (fem_analysis_step(&plain, NET_DT, &err)) fail_msg("plain: %s", err.message);
        /* linearised about this step's start, displaced by 1 cm so the terms are not zero */
        double *uref = malloc((size_t)lin.ndof * sizeof *uref);
        double *vref = malloc((size_t)lin.ndof * sizeof *vref);
        for (int i = 0; i < lin.ndof; i++) {
            uref[i] = lin.cur.u[i] - 0.01 * (i % 3 == 2);
            vref[i] = lin.cur.v[i];
        }
        set_edge_linearisation(&lin, k_n, c_n, uref, vref);
        /* the start state, for the re-solve with the plain force */
        fem_analysis_save(&lin, &err);
        if (fem_analysis_step(&lin, NET_DT, &err)) fail_msg("linearised: %s", err.message);
        if (lin.stats.iterations > plain.stats.iterations + 1) worse++;
        assert_int_equal(lin.stats.iterations <= plain.stats.iterations + 1, 1);
        /* F at the final iterate, written out from the blocks */
        for (int i = 0; i < lin.ndof; i++) {
            double fi = lin.f_coupling[i];
            for (int b = 0; b < 4; b++) {
                if (3 * nodes[2 * b] != i - i % 3) continue;
                int r = i % 3, j = 3 * nodes[2 * b + 1];
                for (int c = 0; c < 3; c++)
                    fi -= K[9 * b + 3 * r + c] * (lin.cur.u[j + c] - uref[j + c]) +
                          C[9 * b + 3 * r + c] * (lin.cur.v[j + c] - vref[j + c]);
            }
            /* same sums in another order: round-off of the ~1e4 N terms */
            assert_near(lin.cur.fc[i], fi, 1e-11 * (fabs(fi) + k_n * 0.02));
        }
        /* solving the step from the same start with the plain force F(u, v) */
        fem_analysis_free(&check);
        assert_int_equal(fem_analysis_init(&check, &m, &err), 0);
        memcpy(check.cur.u, lin.saved.u, (size_t)lin.ndof * sizeof(double));
        memcpy(check.cur.v, lin.saved.v, (size_t)lin.ndof * sizeof(double));
        memcpy(check.cur.a, lin.saved.a, (size_t)lin.ndof * sizeof(double));
        memcpy(check.cur.fd, lin.saved.fd, (size_t)lin.ndof * sizeof(double));
        memcpy(check.cur.fc, lin.saved.fc, (size_t)lin.ndof * sizeof(double));
        check.cur.time_s = lin.saved.time_s;
        memcpy(check.f_coupling, lin.cur.fc, (size_t)lin.ndof * sizeof(double));
        if (fem_analysis_step(&check, NET_DT, &err)) fail_msg("check: %s", err.message);
        double umax = 0;
        for (int i = 0; i < lin.ndof; i++) umax = fmax(umax, fabs(lin.cur.u[i]));
        for (int i = 0; i < lin.ndof; i++)
            /* both are Newton solutions of one equation to the default tolerances
             * (1e-10 relative force, 1e-9 m increment) */
            assert_near(check.cur.u[i], lin.cur.u[i], 1e-9 * umax + 1e-9);
        free(uref);
        free(vref);
    }
    assert_int_equal(worse, 0);
    fem_analysis_free(&plain);
    fem_analysis_free(&lin);
    fem_analysis_free(&check);
    fem_model_free(&m);
}

static void test_newton_iterations(void **state)
{
    (void)state;
    run_newton(FEM_NEWMARK, 0);
    run_newton(FEM_GENERALIZED_ALPHA, 0);
    run_newton(FEM_BOSSAK, 0);
    run_newton(FEM_NEWMARK, 1);   /* modified Newton: CG preconditioned by a kept factor */
}

/* ---- K = C = 0 is the plain path, bit for bit ---------------------------------------- */

static void run_zero(fem_integrator integ, int step_constant)
{
    fem_model m;
    net_model(&m, integ, 1, step_constant);
    fem_analysis a, b;
    nc_error err;
    assert_int_equal(fem_analysis_init(&a, &m, &err), 0);
    assert_int_equal(fem_analysis_init(&b, &m, &err), 0);
    edge_force(&a, 500.0);
    edge_force(&b, 500.0);
    double *uref = calloc((size_t)b.ndof, sizeof *uref), *vref = calloc((size_t)b.ndof, sizeof *vref);
    for (int i = 0; i < b.ndof; i++) { uref[i] = 0.01 * (i % 5); vref[i] = -0.3 * (i % 3); }
    set_edge_linearisation(&b, 0.0, 0.0, uref, vref);
    assert_int_equal(fem_analysis_initial_acceleration(&a, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(&b, &err), 0);
    size_t bytes = (size_t)a.ndof * sizeof(double);
    for (int n = 0; n < 15; n++) {
        double f = 500.0 * (1 + n % 4);   /* a force that changes between steps */
        edge_force(&a, f);
        edge_force(&b, f);
        assert_int_equal(fem_analysis_step(&a, NET_DT, &err), 0);
        assert_int_equal(fem_analysis_step(&b, NET_DT, &err), 0);
        assert_int_equal(memcmp(a.cur.u, b.cur.u, bytes), 0);
        assert_int_equal(memcmp(a.cur.v, b.cur.v, bytes), 0);
        assert_int_equal(memcmp(a.cur.a, b.cur.a, bytes), 0);
        assert_int_equal(memcmp(a.cur.fc, b.cur.fc, bytes), 0);
        assert_int_equal(a.stats.iterations, b.stats.iterations);
    }
    free(uref);
    free(vref);
    fem_analysis_free(&a);
    fem_analysis_free(&b);
    fem_model_free(&m);
}

static void test_zero_jacobian_is_plain(void **state)
{
    (void)state;
    run_zero(FEM_NEWMARK, 0);
    run_zero(FEM_GENERALIZED_ALPHA, 0);
    run_zero(FEM_BOSSAK, 0);
    run_zero(FEM_NEWMARK, 1);
    run_zero(FEM_GENERALIZED_ALPHA, 1);
}

/* ---- the step tangent with edge blocks against finite differences -------------------- */

static void run_tangent(fem_integrator integ)
{
    fem_model m;
    net_model(&m, integ, 0, 0);
    fem_analysis s;
    nc_error err;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    const int nd = s.ndof, ne = s.neq;
    double *uref = calloc((size_t)nd, sizeof(double)), *vref = calloc((size_t)nd, sizeof(double));
    double *u = calloc((size_t)nd, sizeof(double)), *rp = malloc((size_t)nd * sizeof(double));
    double *rm = malloc((size_t)nd * sizeof(double)), *x = calloc((size_t)ne, sizeof(double));
    double *col = malloc((size_t)ne * sizeof(double)), *col0 = malloc((size_t)ne * sizeof(double));
    /* a moving, deflected start state */
    for (int i = 0; i < nd; i++) {
        if (m.fixed[i]) continue;
        s.cur.u[i] = 0.004 * sin(1.0 + i) - (i % 3 == 2 ? 0.02 : 0.0);
        s.cur.v[i] = 0.3 * cos(2.0 + i);
        uref[i] = s.cur.u[i] - 0.003;
        vref[i] = 0.1;
    }
    edge_force(&s, 800.0);
    assert_int_equal(fem_analysis_initial_acceleration(&s, &err), 0);
    /* the end-of-step point where the tangent is checked */
    for (int i = 0; i < nd; i++) u[i] = s.cur.u[i] + (m.fixed[i] ? 0 : 0.002 * cos(3.0 * i));
    const double k_n = 3e4, c_n = 40.0, h = 1e-7;
    const int dofs[6] = {3 * NET_CENTRE, 3 * NET_CENTRE + 1, 3 * NET_CENTRE + 2,
                         3 * NET_EDGE_B, 3 * NET_EDGE_B + 1, 3 * NET_EDGE_B + 2};
    for (int t = 0; t < 6; t++) {
        const int d = dofs[t], q = s.eq[d];
        assert_true(q >= 0);
        /* tangent column without the linearisation */
        fem_analysis_clear_linearisation(&s);
        assert_int_equal(fem_analysis_step_residual(&s, NET_DT, u, rp, &err), 0);
        memset(x, 0, (size_t)ne * sizeof *x);
        x[q] = 1.0;
        fem_sparse_matvec(&s.K, x, col0);
        /* with it */
        set_edge_linearisation(&s, k_n, c_n, uref, vref);
        assert_int_equal(fem_analysis_step_residual(&s, NET_DT, u, rp, &err), 0);
        fem_sparse_matvec(&s.K, x, col);
        /* central differences of the residual (-dr/du is the tangent) */
        double u_d = u[d];
        u[d] = u_d + h;
        assert_int_equal(fem_analysis_step_residual(&s, NET_DT, u, rp, &err), 0);
        u[d] = u_d - h;
        assert_int_equal(fem_analysis_step_residual(&s, NET_DT, u, rm, &err), 0);
        u[d] = u_d;
        double cmax = 0;
        for (int e = 0; e < ne; e++) cmax = fmax(cmax, fabs(col[e]));
        for (int e = 0; e < ne; e++) {
            int de = s.dof_of_eq[e];
            double fd = -(rp[de] - rm[de]) / (2 * h);
            /* O(h^2) truncation of the cable forces and round-off ~1e-13 N / h of the
             * residual: 1e-6 of the largest entry (the inertia term ~4e4 N/m) */
            assert_near(col[e], fd, 1e-6 * cmax);
        }
        /* the linearisation's share alone is exactly K + l_c C (l_c = gamma/(beta dt)),
         * 2 x 2 node blocks, symmetric here */
        double beta, gamma;
        if (integ == FEM_NEWMARK) { beta = m.settings.beta; gamma = m.settings.gamma; }
        else if (integ == FEM_BOSSAK) {
            double am = m.settings.alpha_b;
            gamma = 0.5 - am; beta = 0.25 * (1 - am) * (1 - am);
        } else {
            double r = m.settings.rho_inf, am = (2 * r - 1) / (r + 1), af = r / (r + 1);
            gamma = 0.5 - am + af; beta = 0.25 * (1 - am + af) * (1 - am + af);
        }
        int nodes[8];
        double K[36], C[36];
        edge_blocks(NET_CENTRE, NET_EDGE_B, k_n, c_n, nodes, K, C);
        for (int e = 0; e < ne; e++) {
            int de = s.dof_of_eq[e];
            double expect = 0;
            for (int b = 0; b < 4; b++)
                if (3 * nodes[2 * b] == de - de % 3 && 3 * nodes[2 * b + 1] == d - d % 3) {
                    int k = 3 * (de % 3) + d % 3;
                    expect += K[9 * b + k] + gamma / (beta * NET_DT) * C[9 * b + k];
                }
            /* round-off of the added entries next to ~4e4 N/m */
            assert_near(col[e] - col0[e], expect, 1e-12 * cmax);
        }
    }
    free(uref); free(vref); free(u); free(rp); free(rm); free(x); free(col); free(col0);
    fem_analysis_free(&s);
    fem_model_free(&m);
}

static void test_edge_tangent(void **state)
{
    (void)state;
    run_tangent(FEM_NEWMARK);
    run_tangent(FEM_GENERALIZED_ALPHA);
    run_tangent(FEM_BOSSAK);
}

/* ---- save/restore with a linearisation ----------------------------------------------- */

static void test_restore_bitwise(void **state)
{
    (void)state;
    fem_model m;
    net_model(&m, FEM_GENERALIZED_ALPHA, 1, 1);
    fem_analysis s;
    nc_error err;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    edge_force(&s, 2000.0);
    assert_int_equal(fem_analysis_initial_acceleration(&s, &err), 0);
    size_t bytes = (size_t)s.ndof * sizeof(double);
    double *u1 = malloc(bytes), *v1 = malloc(bytes), *a1 = malloc(bytes), *uref = malloc(bytes);
    for (int n = 0; n < 8; n++) {
        for (int i = 0; i < s.ndof; i++) uref[i] = s.cur.u[i] - 0.002;
        set_edge_linearisation(&s, 1e5, 100.0, uref, s.cur.v);
        assert_int_equal(fem_analysis_save(&s, &err), 0);
        assert_int_equal(fem_analysis_step(&s, NET_DT, &err), 0);
        memcpy(u1, s.cur.u, bytes);
        memcpy(v1, s.cur.v, bytes);
        memcpy(a1, s.cur.a, bytes);
        int it1 = s.stats.iterations;
        /* a second coupling iteration of the same step sets the same linearisation again */
        assert_int_equal(fem_analysis_restore(&s, &err), 0);
        set_edge_linearisation(&s, 1e5, 100.0, uref, s.cur.v);
        assert_int_equal(fem_analysis_step(&s, NET_DT, &err), 0);
        assert_int_equal(memcmp(u1, s.cur.u, bytes), 0);
        assert_int_equal(memcmp(v1, s.cur.v, bytes), 0);
        assert_int_equal(memcmp(a1, s.cur.a, bytes), 0);
        assert_int_equal(it1, s.stats.iterations);
    }
    free(u1); free(v1); free(a1); free(uref);
    fem_analysis_free(&s);
    fem_model_free(&m);
}

/* ---- an unsymmetric K: the matrix holds its symmetric part, the residual all of it, and
 * each Newton step the skew part through GMRES, so Newton keeps its exact tangent --------- */

/* the friction-like coupling (N/m): strong enough that Newton with the symmetric part alone
 * needs clearly more iterations (measured: 2e4 costs one more, 1e5 three more) */
#define SKEW_K 1e5

/* The edge contact of edge_blocks (5e4 N/m, 50 N s/m) with a friction-like part
 * k_t t n^T (tangential force from normal motion) on (a, b) only: an unsymmetric K. */
static int skewed_edge_blocks(int *nodes, double *K, double *C)
{
    const int nb = edge_blocks(NET_CENTRE, NET_EDGE_B, 5e4, 50.0, nodes, K, C);
    const double t[3] = {1, 0, 0}, n[3] = {0, 0, 1};
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) K[9 * 1 + 3 * r + c] += SKEW_K * t[r] * n[c];
    return nb;
}

static void test_unsymmetric(void **state)
{
    (void)state;
    fem_model m;
    net_model(&m, FEM_BOSSAK, 0, 0);
    fem_analysis s, p;
    nc_error err;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    assert_int_equal(fem_analysis_init(&p, &m, &err), 0);
    size_t bytes = (size_t)s.ndof * sizeof(double);
    int nodes[8];
    double K[36], C[36];
    const int nb = skewed_edge_blocks(nodes, K, C);
    double *uref = malloc(bytes), *vref = calloc(1, bytes);
    for (int i = 0; i < s.ndof; i++) uref[i] = -0.02 * (i % 3 == 2);
    edge_force(&s, 1500.0);
    edge_force(&p, 1500.0);
    assert_int_equal(fem_analysis_initial_acceleration(&s, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(&p, &err), 0);
    assert_int_equal(fem_analysis_set_linearisation(&s, uref, vref, nb, nodes, K, C, &err), 0);
    assert_int_equal(fem_analysis_step(&s, NET_DT, &err), 0);
    /* the plain step under F(u, v) of the linearised solution reproduces it */
    memcpy(p.f_coupling, s.cur.fc, bytes);
    assert_int_equal(fem_analysis_step(&p, NET_DT, &err), 0);
    /* the exact tangent: as few Newton iterations as the plain step (+1, as with a symmetric
     * linearisation in test_newton_iterations), every one through GMRES; with the symmetric
     * part alone Newton converges only linearly, at the rate of the skew part */
    print_message("unsymmetric: %d Newton iterations (plain step %d), %ld GMRES steps, %ld GMRES iterations\n",
                  s.stats.iterations, p.stats.iterations, s.stats.gmres_solves, s.stats.gmres_iterations);
    assert_true(s.stats.iterations <= p.stats.iterations + 1);
    assert_true(s.stats.gmres_solves >= s.stats.iterations);
    assert_int_equal(s.stats.gmres_failures, 0);
    assert_int_equal(p.stats.gmres_solves, 0);
    double umax = 0;
    for (int i = 0; i < s.ndof; i++) umax = fmax(umax, fabs(s.cur.u[i]));
    for (int i = 0; i < s.ndof; i++)
        /* two Newton solutions of one equation (default tolerances) */
        assert_near(p.cur.u[i], s.cur.u[i], 1e-9 * umax + 1e-9);
    /* and the unsymmetric part did act: x force on the centre from the edge's z motion */
    double fx = s.cur.fc[3 * NET_CENTRE] - s.f_coupling[3 * NET_CENTRE];
    double expect = 0;
    for (int b = 0; b < nb; b++)
        if (nodes[2 * b] == NET_CENTRE)
            for (int c = 0; c < 3; c++) {
                int j = 3 * nodes[2 * b + 1] + c;
                expect -= K[9 * b + c] * (s.cur.u[j] - uref[j]) + C[9 * b + c] * s.cur.v[j];
            }
    assert_near(fx, expect, 1e-12 * (fabs(expect) + 1.0));
    assert_below(1.0, fabs(expect));
    free(uref); free(vref);
    fem_analysis_free(&s);
    fem_analysis_free(&p);
    fem_model_free(&m);
}

/* The structure's interface compliance (fem_analysis_compliance) after a step solved with an
 * unsymmetric linearisation: S = du/dF without the linearisation, against central
 * differences of the plain step under F(u, v) of the linearised solution +- a force on each
 * of the two edge nodes' dofs; and the rows of every dof of the model (S_rows), against the
 * same differences at each dof. */
static void test_compliance(void **state)
{
    (void)state;
    fem_model m;
    net_model(&m, FEM_BOSSAK, 0, 0);
    m.settings.displacement_tol_m = 1e-14;
    m.settings.relative_tol = 1e-15;
    m.settings.residual_tol_n = 1e-12;
    fem_analysis s, p;
    nc_error err;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    size_t bytes = (size_t)s.ndof * sizeof(double);
    int nodes[8];
    double K[36], C[36];
    const int nb = skewed_edge_blocks(nodes, K, C);
    double *uref = malloc(bytes), *vref = calloc(1, bytes), *up = malloc(bytes);
    for (int i = 0; i < s.ndof; i++) uref[i] = -0.02 * (i % 3 == 2);
    edge_force(&s, 1500.0);
    assert_int_equal(fem_analysis_initial_acceleration(&s, &err), 0);
    assert_int_equal(fem_analysis_save(&s, &err), 0);
    assert_int_equal(fem_analysis_set_linearisation(&s, uref, vref, nb, nodes, K, C, &err), 0);
    assert_int_equal(fem_analysis_step(&s, NET_DT, &err), 0);
    const int dofs[6] = {3 * NET_CENTRE, 3 * NET_CENTRE + 1, 3 * NET_CENTRE + 2,
                         3 * NET_EDGE_B, 3 * NET_EDGE_B + 1, 3 * NET_EDGE_B + 2};
    double S[36];
    int *all = malloc((size_t)s.ndof * sizeof *all);
    double *S_all = malloc(6 * bytes), *col_all = malloc(bytes);
    for (int i = 0; i < s.ndof; i++) all[i] = i;
    assert_int_equal(fem_analysis_compliance(&s, 6, dofs, S, s.ndof, all, S_all, &err), 0);
    const double delta = 1.0;   /* N, against 1500 N: central differences err by O(delta^2) */
    double smax = 0.0, worst = 0.0, worst_rows = 0.0, same_rows = 0.0;
    for (int b = 0; b < 6; b++) {
        double col[6];
        for (int sign = -1; sign <= 1; sign += 2) {
            assert_int_equal(fem_analysis_init(&p, &m, &err), 0);
            memcpy(p.cur.u, s.saved.u, bytes);
            memcpy(p.cur.v, s.saved.v, bytes);
            memcpy(p.cur.a, s.saved.a, bytes);
            memcpy(p.cur.fd, s.saved.fd, bytes);
            memcpy(p.cur.fc, s.saved.fc, bytes);
            memcpy(p.f_coupling, s.cur.fc, bytes);
            p.f_coupling[dofs[b]] += sign * delta;
            assert_int_equal(fem_analysis_step(&p, NET_DT, &err), 0);
            if (sign < 0) memcpy(up, p.cur.u, bytes);
            else {
                for (int a = 0; a < 6; a++) col[a] = (p.cur.u[dofs[a]] - up[dofs[a]]) / (2 * delta);
                for (int i = 0; i < s.ndof; i++) col_all[i] = (p.cur.u[i] - up[i]) / (2 * delta);
            }
            fem_analysis_free(&p);
        }
        for (int a = 0; a < 6; a++) {
            smax = fmax(smax, fabs(S[6 * a + b]));
            worst = fmax(worst, fabs(S[6 * a + b] - col[a]));
            same_rows = fmax(same_rows, fabs(S_all[6 * dofs[a] + b] - S[6 * a + b]));
        }
        for (int i = 0; i < s.ndof; i++)
            worst_rows = fmax(worst_rows, fabs(S_all[6 * i + b] - col_all[i]));
    }
    print_message("compliance: largest entry %.4g m/N, largest difference from central differences %.3g "
                  "(%.3g over the rows of every dof)\n", smax, worst, worst_rows);
    assert_below(worst, 1e-6 * smax);
    assert_below(worst_rows, 1e-6 * smax);
    assert_below(same_rows, 1e-12 * smax);
    free(all); free(S_all); free(col_all);
    /* a node's own direction moves with its force: the diagonal is positive */
    for (int a = 0; a < 6; a++) assert_below(0.0, S[7 * a]);
    free(uref); free(vref); free(up);
    fem_analysis_free(&s);
    fem_model_free(&m);
}

/* ---- the rounding floor ---------------------------------------------------------------- */

/* The Newton iteration's rounding floor under a stiff linearisation: eq. (A.5)'s dashpot at
 * a graze gives K of 1e13-1e16 N/m (docs/notes/interface_jacobian.md item 10). The line
 * model's node starts 0.3 m down, where its two half-metre elements pull with about 17 kN
 * each, held there by a contact of 1e15 N/m across and along: one ulp of its displacement
 * (5.6e-17 m) moves K (u - u^k) by 0.06 N, far above the tolerance of 1e-11 N and its
 * factor 1e3, so no increment reaches either, and Newton failed. The floor now also counts
 * the rounding of the linearisation's K (u - u^k): each step converges at the floor,
 * counted, within 4 ulps of the node's displacement times K, with the node held at u^k to
 * within its other forces over K (the cable's pull and the node's inertia, below 1e5 N:
 * 1e-10 m). */
static void test_stiff_linearisation_floor(void **state)
{
    (void)state;
    static const double held[3] = {0.01, 0.02, -0.3};
    fem_model m;
    line_model(&m, FEM_NEWMARK, 0);
    fem_analysis s;
    nc_error err;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    double uref[9] = {0}, vref[9] = {0}, K[9] = {0}, C[9] = {0};
    for (int c = 0; c < 3; c++) {
        s.cur.u[3 + c] = uref[3 + c] = held[c];
        K[4 * c] = 1e15;
    }
    const int nodes[2] = {1, 1};
    assert_int_equal(fem_analysis_set_linearisation(&s, uref, vref, 1, nodes, K, C, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(&s, &err), 0);
    for (int n = 0; n < 3; n++) {
        int rc = fem_analysis_step(&s, LN_DT, &err);
        print_message("step %d: rc %d, residual %.3g N, %ld solves at the floor, u - u^k %.3g %.3g %.3g m%s%s\n",
                      n, rc, s.stats.residual_norm, s.stats.roundoff_converged,
                      s.cur.u[3] - held[0], s.cur.u[4] - held[1], s.cur.u[5] - held[2],
                      rc ? ": " : "", rc ? err.message : "");
        assert_int_equal(rc, 0);
        for (int c = 0; c < 3; c++) assert_near(s.cur.u[3 + c], held[c], 1e-10);
        /* as near as rounding allows: within 4 ulps of the node's 0.3 m times its K */
        assert_below(s.stats.residual_norm, 4.0 * 1e15 * 0.3 * DBL_EPSILON);
    }
    assert_true(s.stats.roundoff_converged > 0);
    fem_analysis_free(&s);
    fem_model_free(&m);
}

/* ---- statics and rejected blocks ----------------------------------------------------- */

/* statics: F = F^k - K (u - u^k); the solution is the plain static solution under F(u) */
static void test_static(void **state)
{
    (void)state;
    fem_model m;
    net_model(&m, FEM_NEWMARK, 0, 0);
    m.settings.type = FEM_STATIC;
    fem_analysis s, p;
    nc_error err;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    assert_int_equal(fem_analysis_init(&p, &m, &err), 0);
    size_t bytes = (size_t)s.ndof * sizeof(double);
    double *uref = calloc(1, bytes), *vref = calloc(1, bytes);
    for (int i = 0; i < s.ndof; i++) { uref[i] = -0.01 * (i % 3 == 2); vref[i] = 5.0; }
    edge_force(&s, 1000.0);
    set_edge_linearisation(&s, 1e5, 1e3, uref, vref);   /* C has no effect in statics */
    assert_int_equal(fem_analysis_static(&s, 1.0, &err), 0);
    int nodes[8];
    double K[36], C[36];
    edge_blocks(NET_CENTRE, NET_EDGE_B, 1e5, 1e3, nodes, K, C);
    memcpy(p.f_coupling, s.f_coupling, bytes);
    for (int b = 0; b < 4; b++)
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                p.f_coupling[3 * nodes[2 * b] + r] -=
                    K[9 * b + 3 * r + c] * (s.cur.u[3 * nodes[2 * b + 1] + c] - uref[3 * nodes[2 * b + 1] + c]);
    assert_int_equal(fem_analysis_static(&p, 1.0, &err), 0);
    double umax = 0;
    for (int i = 0; i < s.ndof; i++) umax = fmax(umax, fabs(s.cur.u[i]));
    assert_below(1e-3, umax);
    /* two Newton solutions of one equation (default tolerances, 1e-9 m increments) */
    for (int i = 0; i < s.ndof; i++) assert_near(p.cur.u[i], s.cur.u[i], 1e-9 * umax + 1e-9);
    free(uref); free(vref);
    fem_analysis_free(&s);
    fem_analysis_free(&p);
    fem_model_free(&m);
}

/* A particle touching nodes of different elements couples them: the pattern grows by the
 * pair, once, and the step is the plain step under F(u, v) of its solution (as for edge
 * blocks); a repeated step after a restore is bit-identical. Out-of-range nodes are
 * rejected; blocks on supported nodes act only in the residual. */
static void test_grows_pattern_for_unconnected_blocks(void **state)
{
    (void)state;
    fem_model m;
    net_model(&m, FEM_BOSSAK, 0, 0);
    fem_analysis s, p;
    nc_error err;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    assert_int_equal(fem_analysis_init(&p, &m, &err), 0);
    size_t bytes = (size_t)s.ndof * sizeof(double);
    /* a spring of 5e4 N/m between the centre and its diagonal neighbour (no shared element) */
    const int a = NET_CENTRE, b = NET_CENTRE + NET_N + 1;
    int nodes[8] = {a, a, a, b, b, a, b, b};
    double K[36] = {0};
    for (int k = 0; k < 4; k++)
        for (int c = 0; c < 3; c++) K[9 * k + 4 * c] = (k == 0 || k == 3 ? 5e4 : -5e4);
    double *uref = calloc(1, bytes), *vref = calloc(1, bytes), *u1 = malloc(bytes);
    edge_force(&s, 1500.0);
    edge_force(&p, 1500.0);
    assert_int_equal(fem_analysis_initial_acceleration(&s, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(&p, &err), 0);
    const int nnz_before = s.K.nnz;
    assert_int_equal(fem_analysis_set_linearisation(&s, uref, vref, 4, nodes, K, NULL, &err), 0);
    assert_int_equal(s.stats.pattern_growths, 1);
    assert_true(s.K.nnz > nnz_before);
    assert_int_equal(fem_analysis_save(&s, &err), 0);
    assert_int_equal(fem_analysis_step(&s, NET_DT, &err), 0);
    memcpy(u1, s.cur.u, bytes);
    /* the same blocks again: no further growth */
    assert_int_equal(fem_analysis_set_linearisation(&s, uref, vref, 4, nodes, K, NULL, &err), 0);
    assert_int_equal(s.stats.pattern_growths, 1);
    /* the plain step under F(u, v) of the linearised solution reproduces it */
    memcpy(p.f_coupling, s.cur.fc, bytes);
    assert_int_equal(fem_analysis_step(&p, NET_DT, &err), 0);
    double umax = 0;
    for (int i = 0; i < s.ndof; i++) umax = fmax(umax, fabs(s.cur.u[i]));
    for (int i = 0; i < s.ndof; i++) assert_near(p.cur.u[i], s.cur.u[i], 1e-9 * umax + 1e-9);
    /* the spring acted: it pulls the centre towards its neighbour */
    double fz = s.cur.fc[3 * a + 2] - s.f_coupling[3 * a + 2];
    assert_near(fz, -5e4 * (s.cur.u[3 * a + 2] - s.cur.u[3 * b + 2]), 1e-9 * fabs(fz) + 1e-9);
    assert_below(1.0, fabs(fz));
    /* repeated from the saved state (whose factorisation belonged to the old pattern) */
    assert_int_equal(fem_analysis_restore(&s, &err), 0);
    assert_int_equal(fem_analysis_step(&s, NET_DT, &err), 0);
    assert_memory_equal(s.cur.u, u1, bytes);
    /* a node outside the model is still an error; supported nodes act in the residual only */
    int out[2] = {NET_CENTRE, NET_N * NET_N};
    assert_int_equal(fem_analysis_set_linearisation(&s, uref, vref, 1, out, K, NULL, &err), -1);
    assert_int_equal(s.lin.active, 0);
    int support[2] = {0, 1};
    assert_int_equal(fem_analysis_set_linearisation(&s, uref, vref, 1, support, K, NULL, &err), 0);
    fem_analysis_clear_linearisation(&s);
    assert_int_equal(s.lin.active, 0);
    free(uref); free(vref); free(u1);
    fem_analysis_free(&s);
    fem_analysis_free(&p);
    fem_model_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_monolithic_newmark),
        cmocka_unit_test(test_monolithic_generalized_alpha),
        cmocka_unit_test(test_monolithic_bossak),
        cmocka_unit_test(test_monolithic_step_constant),
        cmocka_unit_test(test_newton_iterations),
        cmocka_unit_test(test_zero_jacobian_is_plain),
        cmocka_unit_test(test_edge_tangent),
        cmocka_unit_test(test_restore_bitwise),
        cmocka_unit_test(test_unsymmetric),
        cmocka_unit_test(test_compliance),
        cmocka_unit_test(test_static),
        cmocka_unit_test(test_stiff_linearisation_floor),
        cmocka_unit_test(test_grows_pattern_for_unconnected_blocks),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
