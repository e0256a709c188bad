/* Coupling loops against closed-form in-process participants (cpl_test_models.h):
 * weak lags (first-order error), strong reproduces the monolithic solution, α = 1 diverges
 * exactly where |J| > 1, Aitken beats constant α, IQN-ILS bound, force vs displacement
 * relaxation, the quadratic predictor, efficiency options, no FEM solve repeated for the
 * same input, max-iteration policy, participant
 * errors, interruption, step rejection (failed solve, divergence, dt_min and the policy, with
 * the efficiency options), BEGIN_STEP and ACCEPT_STEP sent to both participants at once. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cpl_test_models.h"
#include "../../coupler/cpl_loop.h"

typedef struct run_result {
    int rc;
    nc_error err;
    cpl_failure failure;
    tm_recorder rec;
    double u_err;            /* max |u − u_monolithic| over the interface after the run */
    double u_mono_scale;     /* max |u_monolithic| */
    long fem_solves, fem_begins, fem_accepts;
    double u[12], v[12];     /* interface state after the run (first 4 nodes) */
    double fem_dt_max;
    cpl_timing timing;
} run_result;

static void run(const tm_problem *pb, const cpl_loop_settings *s, run_result *out,
                void (*tweak)(tm_structure *, tm_particles *))
{
    memset(out, 0, sizeof *out);
    tm_structure st, st_ref;
    tm_particles pa, pa_ref;
    tm_structure_init(&st, pb->nodes, pb->m, pb->k, pb->k_link);
    tm_particles_init(&pa, pb->nodes, pb->mp, pb->kc, pb->g);
    tm_structure_init(&st_ref, pb->nodes, pb->m, pb->k, pb->k_link);
    tm_particles_init(&pa_ref, pb->nodes, pb->mp, pb->kc, pb->g);
    if (tweak) {
        tweak(&st, &pa);
        tweak(&st_ref, &pa_ref);
    }
    cpl_participant fem = tm_structure_participant(&st), dem = tm_particles_participant(&pa);
    cpl_observer obs = tm_recorder_observer(&out->rec);
    cpl_loop *loop;
    assert_int_equal(cpl_loop_create(&loop, s, pb->nodes, NULL, NULL, &out->err), 0);
    out->rc = cpl_loop_run(loop, &fem, &dem, &obs, NULL, &out->failure, &out->err);
    /* monolithic reference with the same step sizes */
    for (long i = 0; i < out->rec.steps && i < 4096; i++)
        tm_monolithic_step(&st_ref, &pa_ref, out->rec.time[i] - out->rec.dt[i], out->rec.dt[i]);
    const double *u = cpl_loop_displacement(loop);
    for (size_t i = 0; i < st.nd; i++) {
        out->u_err = fmax(out->u_err, fabs(u[i] - st_ref.u0[i]));
        out->u_mono_scale = fmax(out->u_mono_scale, fabs(st_ref.u0[i]));
    }
    out->fem_solves = st.solves;
    out->fem_begins = st.begins;
    out->fem_accepts = st.accepts;
    memcpy(out->u, u, sizeof(double) * (st.nd < 12 ? st.nd : 12));
    memcpy(out->v, cpl_loop_velocity(loop), sizeof(double) * (st.nd < 12 ? st.nd : 12));
    out->fem_dt_max = st.dt_seen_max;
    out->timing = *cpl_loop_timing(loop);
    cpl_loop_free(loop);
    tm_structure_free(&st);
    tm_structure_free(&st_ref);
    tm_particles_free(&pa);
    tm_particles_free(&pa_ref);
}

/* Strong coupling with no relaxation on the mild problem equals the monolithic backward-Euler
 * solution: the interface residual 1e-10 per iteration and |J| ≈ 0.1 bound the per-step
 * error by ~1e-10, over 50 steps below 1e-8 (observed ~1e-12). */
static void test_strong_matches_monolithic(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.5);
    run_result r;
    run(&TM_MILD, &s, &r, NULL);
    assert_int_equal(r.rc, 0);
    assert_int_equal(r.rec.steps, 50);
    assert_below(1e-3, r.u_mono_scale);          /* a real response, not a trivial zero */
    assert_below(r.u_err, 1e-8);
    for (long i = 0; i < r.rec.steps; i++) assert_true(r.rec.converged[i]);
}

/* Weak coupling lags: with the constant predictor the particles see last step's interface,
 * an O(Δt) splitting error.
 * Halving Δt must roughly halve the deviation from the monolithic answer (ratio in
 * [1.6, 2.5] for a first-order error), and the deviation is far above strong's. */
static void test_weak_lags_first_order(void **state)
{
    (void)state;
    /* soft contact (ω Δt ≈ 0.03): the asymptotic first-order regime */
    const tm_problem soft = {1, 1.0, 100.0, 0.0, 1.0, 100.0, -9.81};
    run_result r1, r2, r3;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_WEAK, 0.002, 0.3);
    s.predictor = CPL_PREDICT_CONSTANT;   /* the particles see the wall of the last step */
    run(&soft, &s, &r1, NULL);
    s.dt_s = 0.001;
    run(&soft, &s, &r2, NULL);
    /* extrapolating the wall (u + Δt u̇) must reduce that lag */
    s.predictor = CPL_PREDICT_LINEAR;
    run(&soft, &s, &r3, NULL);
    assert_int_equal(r3.rc, 0);
    print_message("weak, linear predictor, dt/2: deviation %.3e\n", r3.u_err);
    assert_below(r3.u_err, 0.5 * r2.u_err);
    assert_int_equal(r1.rc, 0);
    assert_int_equal(r2.rc, 0);
    assert_int_equal(r1.timing.iterations, r1.rec.steps);   /* one exchange per step */
    double ratio = r1.u_err / r2.u_err;
    print_message("weak: deviation from monolithic %.3e (dt), %.3e (dt/2), ratio %.3f\n",
                  r1.u_err, r2.u_err, ratio);
    assert_below(1e-3 * r1.u_mono_scale, r1.u_err);
    assert_below(1.6, ratio);
    assert_below(ratio, 2.5);
}

/* A structure that moves as u(t) = ½ a t² whatever the force (its velocity a t exact), and
 * particles that only record the interface position each step's first iteration gives them:
 * what the predictor guessed. */
typedef struct guess_recorder {
    double accel;            /* m/s² */
    double guess[64], time[64];
    long steps;
} guess_recorder;

static int prescribed_solve(void *ctx, const cpl_call *call, const double *in0,
                            const double *in1, double *out0, double *out1,
                            cpl_solve_info *info, nc_error *err)
{
    (void)in0; (void)in1; (void)info; (void)err;
    const guess_recorder *g = ctx;
    const double t = call->time_s + call->dt_s;
    for (int k = 0; k < 3; k++) {
        out0[k] = 0.5 * g->accel * t * t;
        out1[k] = g->accel * t;
    }
    return 0;
}

static int recording_solve(void *ctx, const cpl_call *call, const double *in0,
                           const double *in1, double *out0, double *out1,
                           cpl_solve_info *info, nc_error *err)
{
    (void)in1; (void)out1; (void)info; (void)err;
    guess_recorder *g = ctx;
    if (call->iteration == 1 && g->steps < 64) {
        g->guess[g->steps] = in0[2];
        g->time[g->steps++] = call->time_s + call->dt_s;
    }
    memset(out0, 0, 3 * sizeof *out0);
    return 0;
}

static int no_op(void *ctx, const cpl_call *call, nc_error *err)
{
    (void)ctx; (void)call; (void)err;
    return 0;
}

/* Each step's first guess of the end-of-step position under a constant acceleration: the
 * quadratic predictor (the default) is exact from the second step on (the parabola through
 * the last two positions with the last velocity as its slope), the linear one misses by
 * ½ a Δt², and without a previous step, or with a step less than half the last one, the
 * quadratic one is the linear one. */
static void test_quadratic_predictor(void **state)
{
    (void)state;
    const double a = -9.81, dt = 0.01;
    for (int quadratic = 0; quadratic <= 1; quadratic++) {
        guess_recorder g = {.accel = a};
        cpl_participant fem = {"fem", &g, no_op, prescribed_solve, no_op, 0, NULL, NULL, NULL, NULL, 0};
        cpl_participant dem = {"dem", &g, no_op, recording_solve, no_op, 0, NULL, NULL, NULL, NULL, 0};
        /* 20 steps of dt, then one of 0.4 dt to end on end_time: too short for the parabola
         * (less than half the last step), so the linear guess again */
        cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_WEAK, dt, 0.204);
        if (quadratic) assert_int_equal(s.predictor, CPL_PREDICT_QUADRATIC);
        s.predictor = quadratic ? CPL_PREDICT_QUADRATIC : CPL_PREDICT_LINEAR;
        cpl_loop *loop;
        nc_error err;
        cpl_failure failure;
        assert_int_equal(cpl_loop_create(&loop, &s, 1, NULL, NULL, &err), 0);
        assert_int_equal(cpl_loop_run(loop, &fem, &dem, NULL, NULL, &failure, &err), 0);
        cpl_loop_free(loop);
        assert_int_equal(g.steps, 21);
        for (long n = 0; n < g.steps; n++) {
            const double h = g.time[n] - (n > 0 ? g.time[n - 1] : 0.0);
            const double exact = 0.5 * a * g.time[n] * g.time[n];
            const double miss = quadratic && n > 0 && n < 20 ? 0.0 : -0.5 * a * h * h;
            assert_near(g.guess[n], exact + miss, 1e-12);
        }
        assert_near(g.time[20] - g.time[19], 0.4 * dt, 1e-12);
    }
}

/* A participant that can send BEGIN_STEP and ACCEPT_STEP in two halves: every call goes
 * to a log shared by both, "P<b|a>:<name>" for a post, "W:<name>" for an await, "B:" and
 * "A:" for begin_step and accept called whole, "S:" for a solve. */
typedef struct posting {
    const char *name;
    char *log;
    size_t size;
    int can_post;
    long fail_await_step;   /* its await fails in this step (-1: never) */
    long step;
} posting;

static void log_call(posting *p, const char *what)
{
    size_t used = strlen(p->log);
    snprintf(p->log + used, p->size - used, "%s:%s ", what, p->name);
}

static int posting_begin(void *ctx, const cpl_call *call, nc_error *err)
{
    (void)call; (void)err;
    log_call(ctx, "B");
    return 0;
}

static int posting_accept(void *ctx, const cpl_call *call, nc_error *err)
{
    (void)call; (void)err;
    log_call(ctx, "A");
    return 0;
}

static int posting_post(void *ctx, cpl_command command, const cpl_call *call, nc_error *err)
{
    (void)err;
    posting *p = ctx;
    p->step = call->step;
    log_call(p, command == CPL_COMMAND_BEGIN_STEP ? "Pb" : "Pa");
    return 0;
}

static int posting_await(void *ctx, nc_error *err)
{
    posting *p = ctx;
    log_call(p, "W");
    if (p->step == p->fail_await_step)
        return nc_error_set(err, CPL_ERR_PARTICIPANT, "%s did not answer", p->name);
    return 0;
}

static int posting_solve(void *ctx, const cpl_call *call, const double *in0, const double *in1,
                         double *out0, double *out1, cpl_solve_info *info, nc_error *err)
{
    (void)call; (void)in0; (void)in1; (void)info; (void)err;
    log_call(ctx, "S");
    memset(out0, 0, 3 * sizeof *out0);
    if (out1) memset(out1, 0, 3 * sizeof *out1);
    return 0;
}

static cpl_participant posting_participant(posting *p)
{
    cpl_participant q = {p->name, p, posting_begin, posting_solve, posting_accept, 0,
                         NULL, NULL, p->can_post ? posting_post : NULL,
                         p->can_post ? posting_await : NULL, 0};
    return q;
}

/* BEGIN_STEP and ACCEPT_STEP go to both participants before the loop waits for either (their
 * round trips overlap); a participant without the two halves is called whole in between; a
 * failed await names its participant and the command. */
static void test_commands_overlap(void **state)
{
    (void)state;
    static const struct {
        int fem_posts, dem_posts;
        long fail_fem, fail_dem;
        const char *first_step;
    } cases[] = {
        {1, 1, -1, -1, "Pb:fem Pb:dem W:fem W:dem S:dem S:fem Pa:fem Pa:dem W:fem W:dem "},
        {0, 1, -1, -1, "Pb:dem B:fem W:dem S:dem S:fem Pa:dem A:fem W:dem "},
        {0, 0, -1, -1, "B:fem B:dem S:dem S:fem A:fem A:dem "},
        {1, 1, -1, 1, NULL},   /* the DEM's await fails in step 1 */
        {1, 1, 2, -1, NULL},   /* the FEM's in step 2 */
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char log[4096] = "";
        posting f = {"fem", log, sizeof log, cases[k].fem_posts, cases[k].fail_fem, 0};
        posting d = {"dem", log, sizeof log, cases[k].dem_posts, cases[k].fail_dem, 0};
        cpl_participant fem = posting_participant(&f), dem = posting_participant(&d);
        cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_WEAK, 0.01, 0.03);
        cpl_loop *loop;
        nc_error err;
        cpl_failure failure;
        assert_int_equal(cpl_loop_create(&loop, &s, 1, NULL, NULL, &err), 0);
        int rc = cpl_loop_run(loop, &fem, &dem, NULL, NULL, &failure, &err);
        cpl_loop_free(loop);
        if (cases[k].first_step) {
            assert_int_equal(rc, 0);
            /* three steps, each the same sequence */
            size_t n = strlen(cases[k].first_step);
            assert_int_equal(strlen(log), 3 * n);
            for (int step = 0; step < 3; step++)
                assert_memory_equal(log + step * n, cases[k].first_step, n);
        } else {
            const int dem_fails = cases[k].fail_dem >= 0;
            assert_int_not_equal(rc, 0);
            assert_ptr_equal(failure.participant, dem_fails ? &dem : &fem);
            assert_int_equal(failure.step, dem_fails ? 1 : 2);
            assert_string_equal(failure.command, "begin_step");
            assert_non_null(strstr(err.message, dem_fails ? "dem did not answer" : "fem did not answer"));
        }
    }
}

/* Largest |J| of the per-dof Gauss–Seidel map (K diagonal: one node, no link). */
static double max_abs_J(const tm_problem *pb, double dt)
{
    tm_structure st;
    tm_particles pa;
    tm_structure_init(&st, pb->nodes, pb->m, pb->k, pb->k_link);
    tm_particles_init(&pa, pb->nodes, pb->mp, pb->kc, pb->g);
    double jmax = 0.0;
    for (size_t i = 0; i < st.nd; i++) {
        double J = dt * dt * pa.kc[i] * pa.mp[i] /
                   ((st.m[i] + dt * dt * st.K[i * st.nd + i]) * (pa.mp[i] + dt * dt * pa.kc[i]));
        jmax = fmax(jmax, J);
    }
    tm_structure_free(&st);
    tm_particles_free(&pa);
    return jmax;
}

/* Structure mass chosen so that max |J| is exactly `target`. */
static tm_problem problem_with_J(double target, double dt)
{
    tm_problem pb = {1, 1.0, 100.0, 0.0, 5.0, 2e4, -9.81};
    double j1 = max_abs_J(&pb, dt);                /* J ∝ 1 / (m + Δt² k) */
    double c = j1 * (pb.m + dt * dt * pb.k);
    pb.m = c / target - dt * dt * pb.k;
    return pb;
}

/* Unrelaxed Gauss–Seidel (α = 1) converges iff |J| < 1: |J| = 0.8 converges, |J| = 1.25
 * diverges (residual grows by |J| per iteration, so after 40 iterations it must have grown
 * by more than 1.25^40 / 10 ≈ 750). */
static void test_alpha_one_diverges_where_theory_says(void **state)
{
    (void)state;
    const double dt = 0.01;
    tm_problem ok = problem_with_J(0.8, dt), bad = problem_with_J(1.25, dt);
    assert_near(max_abs_J(&ok, dt), 0.8, 1e-12);
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, dt, 0.05);
    s.max_iterations = 400;
    run_result r;
    run(&ok, &s, &r, NULL);
    assert_int_equal(r.rc, 0);
    for (long i = 0; i < r.rec.steps; i++) assert_true(r.rec.converged[i]);
    assert_below(r.u_err, 1e-8);

    s.max_iterations = 40;
    s.end_time_s = dt;   /* one step */
    s.dt_min_s = dt;     /* at this Δt: no step rejection */
    run(&bad, &s, &r, NULL);
    assert_int_equal(r.rc, 0);                    /* policy: accept with a warning */
    assert_int_equal(r.rec.converged[0], 0);
    assert_int_equal(r.timing.unconverged_steps, 1);
    assert_below(750.0 * r.rec.step0_residual[0], r.rec.step0_residual[39]);
}

/* The relaxation method by name, one of its keys. */
static void use_method(cpl_loop_settings *s, const char *method)
{
    nc_error err;
    if (cpl_relax_settings_select(&s->relax, method, &err)) fail_msg("%s", err.message);
}

static void set(cpl_loop_settings *s, const char *key, double value)
{
    nc_error err;
    if (cpl_relax_settings_set(&s->relax, key, value, &err)) fail_msg("%s", err.message);
}

static long total_iterations(const tm_problem *pb, const char *method, double alpha,
                             cpl_relaxed_quantity q, double *u_err)
{
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.2);
    use_method(&s, method);
    s.relax.alpha = alpha;
    set(&s, "first_iteration_cap", 0.5);
    set(&s, "reuse_steps", 0);
    s.relaxed = q;
    s.tol_abs = 1e-9;
    run_result r;
    run(pb, &s, &r, NULL);
    assert_int_equal(r.rc, 0);
    for (long i = 0; i < r.rec.steps; i++) assert_true(r.rec.converged[i]);
    if (u_err) *u_err = r.u_err;
    return r.timing.iterations;
}

/* |J| ≈ 45 with force relaxation: α = 1 diverges, constant α = 0.02 converges (rate
 * |1 − α (1 − J)| ≈ 0.1 for the stiffest dof, slower for the others), Aitken finds the factor
 * itself and needs fewer iterations. Same with displacement relaxation on a |J| = 0.8 problem
 * and α = 0.5 (in algorithm 2 the u̇ block has its own α; with a small constant α it would
 * converge only at rate 1 − α). All reach the monolithic answer (1e-7). */
static void test_aitken_fewer_iterations_than_constant(void **state)
{
    (void)state;
    double e_const, e_aitken;
    long n_const = total_iterations(&TM_HARD, "constant", 0.02, CPL_RELAXED_FORCE, &e_const);
    long n_aitken = total_iterations(&TM_HARD, "aitken", 0.02, CPL_RELAXED_FORCE, &e_aitken);
    print_message("force relaxation, 20 steps: constant %ld, aitken %ld iterations\n", n_const,
                  n_aitken);
    assert_true(n_aitken < n_const);
    assert_below(e_const, 1e-7);
    assert_below(e_aitken, 1e-7);
    tm_problem p08 = problem_with_J(0.8, 0.01);
    n_const = total_iterations(&p08, "constant", 0.5, CPL_RELAXED_DISPLACEMENT_VELOCITY,
                               &e_const);
    n_aitken = total_iterations(&p08, "aitken", 0.5, CPL_RELAXED_DISPLACEMENT_VELOCITY,
                                &e_aitken);
    print_message("u/v relaxation, |J| = 0.8: constant %ld, aitken %ld iterations\n", n_const,
                  n_aitken);
    assert_true(n_aitken < n_const);
    assert_below(e_const, 1e-7);
    assert_below(e_aitken, 1e-7);
}

/* IQN-ILS on the linear hard problem (2 linked nodes): at most n + 1 quasi-Newton updates
 * per step for n relaxed unknowns, i.e. convergence detected by iteration n + 2 for
 * algorithm 2 (n = 12) and n + 3 for algorithm 3 (n = 6; its first iteration starts from
 * the predicted position, not from the map). */
static void test_iqn_bound_on_linear_problem(void **state)
{
    (void)state;
    for (int mode = 0; mode < 2; mode++) {
        cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.1);
        use_method(&s, "iqn-ils");
        s.relax.alpha = 0.02;
        set(&s, "reuse_steps", 0);
        set(&s, "filter", 1e-10);   /* keep every independent column: exact for linear */
        s.relaxed = mode ? CPL_RELAXED_FORCE : CPL_RELAXED_DISPLACEMENT_VELOCITY;
        s.tol_abs = 1e-9;
        run_result r;
        run(&TM_HARD, &s, &r, NULL);
        assert_int_equal(r.rc, 0);
        int bound = mode ? 6 + 3 : 12 + 2, worst = 0;
        for (long i = 0; i < r.rec.steps; i++) {
            assert_true(r.rec.converged[i]);
            assert_true(r.rec.iterations[i] <= bound);
            if (r.rec.iterations[i] > worst) worst = r.rec.iterations[i];
        }
        print_message("iqn-ils, %s relaxation: at most %d iterations per step (bound %d)\n",
                      mode ? "force" : "u/v", worst, bound);
        assert_below(r.u_err, 1e-7);
    }
}

/* Algorithm 2 (u, u̇) and algorithm 3 (F) relaxation converge to the same monolithic
 * solution (1e-7) on the hard problem, with constant α and with Aitken. */
static void test_force_vs_displacement_relaxation(void **state)
{
    (void)state;
    double e1, e2, e3;
    long n_disp = total_iterations(&TM_HARD, "aitken", 0.02,
                                   CPL_RELAXED_DISPLACEMENT_VELOCITY, &e1);
    long n_force = total_iterations(&TM_HARD, "aitken", 0.02, CPL_RELAXED_FORCE, &e2);
    long n_force_const = total_iterations(&TM_HARD, "constant", 0.02, CPL_RELAXED_FORCE, &e3);
    print_message("aitken: displacement %ld, force %ld iterations; constant force %ld\n",
                  n_disp, n_force, n_force_const);
    assert_below(e1, 1e-7);
    assert_below(e2, 1e-7);
    assert_below(e3, 1e-7);
    assert_true(n_force < n_force_const);
}

static void far_until(tm_structure *s, tm_particles *p)
{
    (void)s;
    p->far_until_s = 0.1;
}

/* Efficiency option (i): Δt × 10 while the DEM reports nobody near the interface; back to Δt
 * once it does; the last step ends exactly at end_time. */
static void test_far_step_option(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_WEAK, 0.001, 0.2);
    s.far_step = 1;
    s.far_step_factor = 10.0;
    run_result r;
    run(&TM_MILD, &s, &r, far_until);
    assert_int_equal(r.rc, 0);
    assert_near(r.rec.dt[0], 0.001, 1e-15);   /* nothing known yet: nominal */
    assert_near(r.rec.dt[1], 0.01, 1e-15);
    assert_near(r.fem_dt_max, 0.01, 1e-15);
    assert_near(r.rec.dt[r.rec.steps - 1], 0.001, 1e-12);
    assert_near(r.rec.time[r.rec.steps - 1], 0.2, 1e-12);
    /* 0.001 + 9 × 0.01 = 0.091 < 0.1, then a large step to 0.101, then 99 small ones */
    assert_int_equal(r.rec.steps, 1 + 10 + 99);
}

static void no_gravity(tm_structure *s, tm_particles *p)
{
    (void)s;
    for (size_t i = 0; i < p->nd; i++) p->g[i] = 0.0;
}

/* Efficiency option (ii): with no load nothing moves, all contact forces are 0 and the FEM is
 * never asked anything (no begin, solve or accept); with gravity it is solved every step. */
static void test_skip_fem_without_contact(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.1);
    s.skip_fem_without_contact = 1;
    run_result r;
    run(&TM_MILD, &s, &r, no_gravity);
    assert_int_equal(r.rc, 0);
    assert_int_equal(r.fem_solves, 0);
    assert_int_equal(r.fem_begins, 0);
    run(&TM_MILD, &s, &r, NULL);
    assert_true(r.fem_solves >= 10);
    assert_int_equal(r.fem_begins, 10);
    assert_below(r.u_err, 1e-8);   /* still the monolithic answer */
}

/* No contact, a moving structure: the particles exert no force (kc = 0) on a structure set
 * swinging by its initial velocity. Each step's FEM input is then the zero force of its first
 * solve again, so only that solve is sent (fem_repeats_skipped counts the others); the
 * iteration still runs to the tolerance (the half step of Aitken's first iteration, then its
 * full step) and the structure follows its free swing, the monolithic answer. With a force
 * that changes between iterations (gravity on the particles, a spring contact) every
 * iteration solves the FEM. */
static void swinging_free(tm_structure *s, tm_particles *p)
{
    for (size_t i = 0; i < s->nd; i++) s->v0[i] = s->v[i] = 1.0;
    for (size_t i = 0; i < p->nd; i++) p->kc[i] = 0.0;
}

static void test_fem_not_solved_again_for_same_input(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.1);
    run_result r;
    run(&TM_MILD, &s, &r, swinging_free);
    assert_int_equal(r.rc, 0);
    assert_int_equal(r.rec.steps, 10);
    for (long i = 0; i < r.rec.steps; i++) assert_true(r.rec.converged[i]);
    assert_true(r.timing.iterations > r.rec.steps);              /* the iteration ran on */
    /* one FEM solve per step, and one more: the restore check repeats its first answer */
    assert_int_equal(r.timing.fem_solves, r.rec.steps + 1);
    assert_int_equal(r.timing.fem_repeats_skipped, r.timing.iterations - r.rec.steps);
    /* none of the skipped reached the FEM: the coupler's count is the participant's own */
    assert_int_equal(r.fem_solves, r.timing.fem_solves);
    assert_below(1e-3, r.u_mono_scale);                           /* it did swing */
    assert_below(r.u_err, 1e-12);
    run(&TM_MILD, &s, &r, NULL);
    assert_int_equal(r.rc, 0);
    assert_int_equal(r.timing.fem_repeats_skipped, 0);
    assert_int_equal(r.timing.fem_solves, r.timing.iterations + 1);
    assert_int_equal(r.fem_solves, r.timing.fem_solves);
}

static void test_max_iterations_stop_policy(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.1);
    s.max_iterations = 5;
    s.on_max_iterations = CPL_MAXIT_STOP;
    s.dt_min_s = s.dt_s;   /* the policy at the nominal Δt: no step rejection */
    run_result r;
    run(&TM_HARD, &s, &r, NULL);   /* α = 1 on |J| ≈ 45 cannot converge */
    assert_int_equal(r.rc, -1);
    assert_int_equal(r.err.code, CPL_ERR_NOT_CONVERGED);
    assert_non_null(strstr(r.err.message, "step 0"));
    assert_non_null(strstr(r.err.message, "after 5 iterations"));
}

static void fem_fails(tm_structure *s, tm_particles *p)
{
    (void)p;
    s->fail_step = 3;
    s->fail_iteration = 2;
}

static void test_participant_error_names_where(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.1);
    use_method(&s, "aitken");
    s.relax.alpha = 0.02;
    run_result r;
    run(&TM_HARD, &s, &r, fem_fails);
    assert_int_equal(r.rc, -1);
    assert_non_null(r.failure.participant);
    assert_string_equal(r.failure.participant->name, "fem");
    assert_int_equal(r.failure.step, 3);
    assert_int_equal(r.failure.iteration, 2);
    assert_non_null(strstr(r.err.message, "fem: step 3"));
    assert_non_null(strstr(r.err.message, "iteration 2"));
    assert_non_null(strstr(r.err.message, "Newton did not converge"));
    assert_int_equal(r.rec.steps, 3);   /* steps 0..2 were accepted */
}

static void test_interrupt_flag(void **state)
{
    (void)state;
    tm_structure st;
    tm_particles pa;
    tm_structure_init(&st, 1, 1.0, 100.0, 0.0);
    tm_particles_init(&pa, 1, 1.0, 1000.0, -9.81);
    cpl_participant fem = tm_structure_participant(&st), dem = tm_particles_participant(&pa);
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.1);
    cpl_loop *loop;
    nc_error err;
    cpl_failure failure;
    volatile sig_atomic_t stop = 1;
    assert_int_equal(cpl_loop_create(&loop, &s, 1, NULL, NULL, &err), 0);
    assert_int_equal(cpl_loop_run(loop, &fem, &dem, NULL, &stop, &failure, &err), -1);
    assert_int_equal(err.code, CPL_ERR_INTERRUPTED);
    assert_null(failure.participant);
    assert_int_equal(st.begins, 0);
    cpl_loop_free(loop);
    tm_structure_free(&st);
    tm_particles_free(&pa);
}

/* ---- step rejection ------------------------------------------------------------------ */

/* Largest |J| with the contact stiffness scaled by `factor`. */
static double max_abs_J_kc(const tm_problem *pb, double dt, double factor)
{
    tm_problem stiff = *pb;
    stiff.kc *= factor;
    return max_abs_J(&stiff, dt);
}

/* A piece of a run with a fixed step (the last one shortened to end on t1). */
typedef struct segment {
    double t0, t1, dt;
} segment;

/* The same participants run segment after segment with fixed steps (no rejection possible:
 * dt_min = dt), each loop starting from the interface state the previous one ended with. */
static void run_segments(const tm_problem *pb, const cpl_loop_settings *base, const segment *seg,
                         int n_seg, void (*tweak)(tm_structure *, tm_particles *),
                         double u_end[12], double v_end[12], long *steps)
{
    tm_structure st;
    tm_particles pa;
    tm_structure_init(&st, pb->nodes, pb->m, pb->k, pb->k_link);
    tm_particles_init(&pa, pb->nodes, pb->mp, pb->kc, pb->g);
    if (tweak) tweak(&st, &pa);
    cpl_participant fem = tm_structure_participant(&st), dem = tm_particles_participant(&pa);
    double u[12] = {0}, v[12] = {0};
    *steps = 0;
    for (int i = 0; i < n_seg; i++) {
        cpl_loop_settings s = *base;
        s.start_time_s = seg[i].t0;
        s.end_time_s = seg[i].t1;
        s.dt_s = seg[i].dt;
        s.dt_min_s = seg[i].dt;
        cpl_loop *loop;
        nc_error err;
        assert_int_equal(cpl_loop_create(&loop, &s, pb->nodes, u, v, &err), 0);
        if (cpl_loop_run(loop, &fem, &dem, NULL, NULL, NULL, &err)) fail_msg("%s", err.message);
        assert_int_equal(cpl_loop_timing(loop)->rejected_attempts, 0);
        memcpy(u, cpl_loop_displacement(loop), 3 * pb->nodes * sizeof(double));
        memcpy(v, cpl_loop_velocity(loop), 3 * pb->nodes * sizeof(double));
        *steps += cpl_loop_timing(loop)->steps;
        cpl_loop_free(loop);
    }
    memcpy(u_end, u, sizeof u);
    memcpy(v_end, v, sizeof v);
    tm_structure_free(&st);
    tm_particles_free(&pa);
}

/* The accepted steps follow the segments exactly; the last ends exactly on the end time. */
static void expect_schedule(const tm_recorder *r, const segment *seg, int n_seg)
{
    long i = 0;
    for (int j = 0; j < n_seg; j++) {
        double t = seg[j].t0;
        while (t < seg[j].t1 - 1e-9 * seg[j].dt) {
            double dt = fmin(seg[j].dt, seg[j].t1 - t);
            assert_true(i < r->steps);
            assert_near(r->dt[i], dt, 1e-15);
            t += dt;
            assert_near(r->time[i], t, 1e-12);
            i++;
        }
    }
    assert_int_equal(r->steps, i);
    assert_near(r->time[r->steps - 1], seg[n_seg - 1].t1, 0.0);
}

/* Nominal 0.01 s; trouble in [0.05, 0.08) that Δt 0.005 cures; grow_after 4: the step at 0.05
 * is rejected, four half steps, back to 0.01 at 0.07, rejected again (still in the window),
 * four half steps to 0.09, nominal to 0.15, and a last half step to the end time 0.155. */
static const segment WINDOW_SCHEDULE[] = {{0.0, 0.05, 0.01}, {0.05, 0.09, 0.005},
                                          {0.09, 0.155, 0.01}};

static void fem_fails_in_window(tm_structure *s, tm_particles *p)
{
    (void)p;
    s->fail = (tm_fail_window){0.05, 0.08, 0.005, 0};
}

static void dem_fails_in_window(tm_structure *s, tm_particles *p)
{
    (void)s;
    p->fail = (tm_fail_window){0.05, 0.08, 0.005, 0};
}

static void stiff_in_window(tm_structure *s, tm_particles *p)
{
    (void)s;
    p->stiff_from_s = 0.05;
    p->stiff_until_s = 0.08;
    p->stiff_factor = 3.0;
}

static void no_gravity_dem_fails_in_window(tm_structure *s, tm_particles *p)
{
    for (size_t i = 0; i < p->nd; i++) p->g[i] = 0.0;
    dem_fails_in_window(s, p);
}

/* Checks a run with the window schedule: two rejections (steps 5 and 9, each retried at
 * half the step), the schedule, and the end state equal to the segment-wise run at the
 * small Δt over the rejected interval: a retry starts from exactly the accepted state, so
 * the two do the same arithmetic (observed 1e-16; tolerance 1e-12 m, 1e-10 m/s for |u| ≈
 * 0.06 m); strong also equals the monolithic solution with the same steps (1e-8, as
 * test_strong_matches_monolithic). */
static void check_window_run(const tm_problem *pb, const cpl_loop_settings *s, const run_result *r,
                             void (*tweak)(tm_structure *, tm_particles *),
                             cpl_reject_reason reason)
{
    if (r->rc) fail_msg("%s", r->err.message);
    expect_schedule(&r->rec, WINDOW_SCHEDULE, 3);
    assert_int_equal(r->rec.rejections, 2);
    assert_int_equal(r->timing.rejected_attempts, 2);
    assert_int_equal(r->timing.reduced_steps, 2);
    assert_int_equal(r->timing.unconverged_steps, 0);
    assert_near(r->timing.min_dt_s, 0.005, 1e-15);
    const long steps[2] = {5, 9};
    for (int i = 0; i < 2; i++) {
        const cpl_reject_record *j = &r->rec.reject[i];
        assert_int_equal(j->step, steps[i]);
        assert_int_equal(j->attempt, 0);
        assert_int_equal(j->reason, reason);
        assert_near(j->dt_s, 0.01, 1e-15);
        assert_near(j->next_dt_s, 0.005, 1e-15);
        assert_int_equal(r->rec.rejected[steps[i]], 1);
    }
    assert_near(r->rec.reject[0].time_s, 0.05, 1e-12);
    assert_near(r->rec.reject[1].time_s, 0.07, 1e-12);
    double u[12], v[12];
    long ref_steps;
    run_segments(pb, s, WINDOW_SCHEDULE, 3, tweak, u, v, &ref_steps);
    assert_int_equal(ref_steps, r->rec.steps);
    double du = 0.0, dv = 0.0;
    for (size_t i = 0; i < 3 * pb->nodes; i++) {
        assert_near(r->u[i], u[i], 1e-12);
        assert_near(r->v[i], v[i], 1e-10);
        du = fmax(du, fabs(r->u[i] - u[i]));
        dv = fmax(dv, fabs(r->v[i] - v[i]));
    }
    print_message("%s, %s rejections: |u - u_segments| %.1e m, |v - v_segments| %.1e m/s, "
                  "|u - u_monolithic| %.1e m (|u| %.1e m)\n",
                  s->scheme == CPL_SCHEME_STRONG ? "strong" : "weak",
                  cpl_reject_reason_text(reason), du, dv, r->u_err, r->u_mono_scale);
    if (s->scheme == CPL_SCHEME_STRONG) {
        assert_below(1e-4, r->u_mono_scale);
        assert_below(r->u_err, 1e-8);
    }
}

/* A solve that fails with CPL_ERR_STEP_FAILED above Δt 0.005 inside the window: strong and
 * weak retry it at half the step and grow back after grow_after steps. */
static void test_rejection_on_failed_solve(void **state)
{
    (void)state;
    for (int weak = 0; weak < 2; weak++) {
        cpl_loop_settings s = tm_loop_settings(weak ? CPL_SCHEME_WEAK : CPL_SCHEME_STRONG, 0.01, 0.155);
        run_result r;
        run(&TM_MILD, &s, &r, fem_fails_in_window);
        check_window_run(&TM_MILD, &s, &r, fem_fails_in_window, CPL_REJECT_STEP_FAILED);
        /* every try of a step is begun: 20 accepted steps + 2 rejected tries */
        assert_int_equal(r.fem_begins, 22);
        assert_int_equal(r.fem_accepts, 20);
    }
}

/* Unrelaxed Gauss–Seidel whose contact is 3× stiffer in the window: |J| > 1 there at Δt 0.01
 * (diverges), < 1 at 0.005 and outside the window: the non-converged steps are rejected
 * and converge at half the step — after max_iterations with reject_slow off, at iteration
 * CPL_SLOW_FIRST with it on (a growing residual cannot reach the tolerance), with the same
 * results. */
static void test_rejection_on_divergence(void **state)
{
    (void)state;
    tm_problem pb = problem_with_J(0.6, 0.01);
    assert_below(1.1, max_abs_J_kc(&pb, 0.01, 3.0));
    assert_below(max_abs_J_kc(&pb, 0.005, 3.0), 0.9);
    for (int slow = 0; slow < 2; slow++) {
        cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.155);
        s.reject_slow = slow;
        run_result r;
        run(&pb, &s, &r, stiff_in_window);
        check_window_run(&pb, &s, &r, stiff_in_window,
                         slow ? CPL_REJECT_TOO_SLOW : CPL_REJECT_NOT_CONVERGED);
        assert_int_equal(r.rec.reject[0].iterations, slow ? CPL_SLOW_FIRST : s.max_iterations);
        assert_int_equal(r.timing.slow_rejections, slow ? 2 : 0);
        for (long i = 0; i < r.rec.steps; i++) assert_true(r.rec.converged[i]);
    }
}

/* reject_slow on a window where the iteration converges, but too slowly: |J| ≈ 0.93 at
 * Δt 0.01 shrinks the residual by 0.93 per iteration, too slowly for
 * max_iterations 50: the try is given up at iteration CPL_SLOW_FIRST and converges at half
 * the step; with max_iterations 400 the same rate is fast enough and nothing is rejected;
 * at dt_min (no smaller step left) the try runs on to max_iterations and is accepted
 * unconverged. */
static void test_reject_slow_convergence(void **state)
{
    (void)state;
    tm_problem pb = problem_with_J(0.458, 0.01);
    const double j_window = max_abs_J_kc(&pb, 0.01, 3.0);
    assert_below(0.9, j_window);
    assert_below(j_window, 0.97);
    assert_below(max_abs_J_kc(&pb, 0.005, 3.0), 0.5);
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.155);
    run_result r;
    run(&pb, &s, &r, stiff_in_window);
    check_window_run(&pb, &s, &r, stiff_in_window, CPL_REJECT_TOO_SLOW);
    assert_int_equal(r.rec.reject[0].iterations, CPL_SLOW_FIRST);
    assert_int_equal(r.timing.slow_rejections, 2);

    s.max_iterations = 400;
    run(&pb, &s, &r, stiff_in_window);
    assert_int_equal(r.rc, 0);
    assert_int_equal(r.timing.rejected_attempts, 0);
    assert_int_equal(r.timing.unconverged_steps, 0);

    s.max_iterations = 50;
    s.dt_min_s = s.dt_s;
    run(&pb, &s, &r, stiff_in_window);
    assert_int_equal(r.rc, 0);
    assert_int_equal(r.timing.rejected_attempts, 0);
    assert_below(0, r.timing.unconverged_steps);
    assert_int_equal(r.rec.converged[5], 0);
}

/* Never converges: the added-mass limit (contact far stiffer than 1/Δt², particle 10× the
 * node's mass: |J| ≈ m_p / m ≈ 10 at every Δt down to dt_min). Six halvings to dt/64, then
 * the policy: "accept" accepts and counts every step (status unreliable), "stop" stops at
 * dt_min naming the retries. */
static void test_never_converges_policy_at_dt_min(void **state)
{
    (void)state;
    const tm_problem never = {1, 1.0, 100.0, 0.0, 10.0, 1e12, -9.81};
    assert_below(9.0, max_abs_J(&never, 0.01 / 64.0));
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.01);
    s.max_iterations = 4;
    s.max_steps = 3;
    run_result r;
    run(&never, &s, &r, NULL);
    assert_int_equal(r.rc, 0);
    assert_int_equal(r.rec.steps, 3);
    assert_int_equal(r.timing.rejected_attempts, 6);
    assert_int_equal(r.timing.reduced_steps, 1);
    assert_int_equal(r.timing.unconverged_steps, 3);
    assert_near(r.timing.min_dt_s, 0.01 / 64.0, 1e-18);
    assert_int_equal(r.rec.rejected[0], 6);
    assert_int_equal(r.rec.rejected[1], 0);
    for (int i = 0; i < 6; i++) {
        assert_near(r.rec.reject[i].dt_s, 0.01 / (double)(1 << i), 1e-18);
        assert_near(r.rec.reject[i].next_dt_s, 0.01 / (double)(2 << i), 1e-18);
        assert_int_equal(r.rec.reject[i].attempt, i);
    }
    for (long i = 0; i < 3; i++) {
        assert_near(r.rec.dt[i], 0.01 / 64.0, 1e-18);
        assert_int_equal(r.rec.converged[i], 0);
    }

    s.on_max_iterations = CPL_MAXIT_STOP;
    run(&never, &s, &r, NULL);
    assert_int_equal(r.rc, -1);
    assert_int_equal(r.err.code, CPL_ERR_NOT_CONVERGED);
    assert_int_equal(r.rec.steps, 0);
    assert_int_equal(r.rec.rejections, 6);
    assert_non_null(strstr(r.err.message, "after 6 rejected tries"));
    assert_non_null(strstr(r.err.message, "dt_min"));

    /* a dt_min of its own: dt / 8 is three halvings */
    s.on_max_iterations = CPL_MAXIT_ACCEPT;
    s.dt_min_s = 0.01 / 8.0;
    run(&never, &s, &r, NULL);
    assert_int_equal(r.rc, 0);
    assert_int_equal(r.timing.rejected_attempts, 3);
    assert_near(r.rec.dt[0], 0.01 / 8.0, 1e-18);
}

static void fem_always_fails(tm_structure *s, tm_particles *p)
{
    (void)p;
    s->fail = (tm_fail_window){0.0, INFINITY, 0.0, 0};
}

/* A solve that fails at every Δt: retried down to dt_min, then the run ends naming the
 * participant and the retries (a failed solve has nothing to accept). */
static void test_failed_solve_at_dt_min_ends_run(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.1);
    run_result r;
    run(&TM_MILD, &s, &r, fem_always_fails);
    assert_int_equal(r.rc, -1);
    assert_int_equal(r.err.code, CPL_ERR_STEP_FAILED);
    assert_non_null(r.failure.participant);
    assert_string_equal(r.failure.participant->name, "fem");
    assert_int_equal(r.rec.steps, 0);
    assert_int_equal(r.rec.rejections, 6);
    assert_non_null(strstr(r.err.message, "fem: step 0"));
    assert_non_null(strstr(r.err.message, "after 6 rejected tries"));
}

/* With skip_fem_without_contact the FEM's step begins at its first solve:
 * - no load: a DEM failure is retried and the FEM still never gets any command;
 * - gravity: a FEM failure is retried with a BEGIN_STEP at the same start time (the FEM
 *   restores), every accepted step is accepted once, the answer is the monolithic one. */
static void test_rejection_with_skip_fem(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.155);
    s.skip_fem_without_contact = 1;
    run_result r;
    run(&TM_MILD, &s, &r, no_gravity_dem_fails_in_window);
    if (r.rc) fail_msg("%s", r.err.message);
    expect_schedule(&r.rec, WINDOW_SCHEDULE, 3);
    assert_int_equal(r.timing.rejected_attempts, 2);
    assert_int_equal(r.fem_begins, 0);
    assert_int_equal(r.fem_solves, 0);
    assert_int_equal(r.fem_accepts, 0);

    run(&TM_MILD, &s, &r, fem_fails_in_window);
    check_window_run(&TM_MILD, &s, &r, fem_fails_in_window, CPL_REJECT_STEP_FAILED);
    assert_int_equal(r.fem_begins, 22);
    assert_int_equal(r.fem_accepts, 20);
}

static void far_until_fem_fails_near(tm_structure *s, tm_particles *p)
{
    p->far_until_s = 0.1;
    s->fail = (tm_fail_window){0.03, 0.2, 0.001, 0};
}

/* Efficiency option (i): an enlarged step that fails is retried at the nominal Δt (not half
 * the enlarged one); nothing below the nominal step is needed. */
static void test_rejected_far_step_retries_nominal(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_WEAK, 0.001, 0.2);
    s.far_step = 1;
    s.far_step_factor = 10.0;
    run_result r;
    run(&TM_MILD, &s, &r, far_until_fem_fails_near);
    if (r.rc) fail_msg("%s", r.err.message);
    assert_below(0, r.rec.rejections);
    for (long i = 0; i < r.rec.rejections && i < 64; i++) {
        assert_near(r.rec.reject[i].dt_s, 0.01, 1e-15);
        assert_near(r.rec.reject[i].next_dt_s, 0.001, 1e-15);
    }
    assert_near(r.timing.min_dt_s, 0.001, 1e-15);
    for (long i = 0; i < r.rec.steps; i++)
        if (r.rec.time[i] > 0.03 + 1e-12) assert_near(r.rec.dt[i], 0.001, 1e-15);
    assert_near(r.rec.time[r.rec.steps - 1], 0.2, 0.0);
}

static void test_settings_check(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.1);
    nc_error err;
    s.tol_abs = 0.0;
    assert_int_equal(cpl_loop_settings_check(&s, "coupler.json", &err), -1);
    assert_non_null(strstr(err.message, "coupler.json: tolerance"));
    s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.1);
    use_method(&s, "aitken");
    set(&s, "alpha_min", 1.0);
    set(&s, "alpha_max", 0.5);
    assert_int_equal(cpl_loop_settings_check(&s, "coupler.json", &err), -1);
    s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.1);
    s.dt_min_s = 0.02;
    assert_int_equal(cpl_loop_settings_check(&s, "coupler.json", &err), -1);
    assert_non_null(strstr(err.message, "step_control.dt_min"));
    s.dt_min_s = 0.0;
    s.grow_after = 0;
    assert_int_equal(cpl_loop_settings_check(&s, "coupler.json", &err), -1);
    assert_non_null(strstr(err.message, "step_control.grow_after"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_strong_matches_monolithic),
        cmocka_unit_test(test_weak_lags_first_order),
        cmocka_unit_test(test_quadratic_predictor),
        cmocka_unit_test(test_commands_overlap),
        cmocka_unit_test(test_alpha_one_diverges_where_theory_says),
        cmocka_unit_test(test_aitken_fewer_iterations_than_constant),
        cmocka_unit_test(test_iqn_bound_on_linear_problem),
        cmocka_unit_test(test_force_vs_displacement_relaxation),
        cmocka_unit_test(test_far_step_option),
        cmocka_unit_test(test_skip_fem_without_contact),
        cmocka_unit_test(test_fem_not_solved_again_for_same_input),
        cmocka_unit_test(test_max_iterations_stop_policy),
        cmocka_unit_test(test_participant_error_names_where),
        cmocka_unit_test(test_interrupt_flag),
        cmocka_unit_test(test_rejection_on_failed_solve),
        cmocka_unit_test(test_rejection_on_divergence),
        cmocka_unit_test(test_reject_slow_convergence),
        cmocka_unit_test(test_never_converges_policy_at_dt_min),
        cmocka_unit_test(test_failed_solve_at_dt_min_ends_run),
        cmocka_unit_test(test_rejection_with_skip_fem),
        cmocka_unit_test(test_rejected_far_step_retries_nominal),
        cmocka_unit_test(test_settings_check),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
