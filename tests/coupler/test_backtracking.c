/* Contact backtracking of the strong loop (coupler.json contact_backtracking) on a problem
 * whose interface Newton iteration leaves the contact and comes back to it for ever.
 *
 * One net node (mass m on a spring k to the ground, backward Euler, z only) and a rigid
 * obstacle coming down at speed V that touches it at t = 0. The "DEM" returns the end-of-step
 * force F = −kc pen^p (pen = u + V t₁, the obstacle's overlap with the node, > 0 in contact)
 * and its exact derivative K = −dF/du = kc p pen^(p−1); the "FEM" solves its step with the
 * linearised force F^k − K (u − u^k). For p < 1 (a concave law: the force rises steeply at
 * first contact, as a dashpot-dominated contact does) the tangent of pen^p meets zero at
 * pen (1 − 1/p) < 0: every Newton step from a contact iterate lands beyond the contact, where
 * F = 0 and K = 0, and the FEM's contact-free answer is the deep contact again (a cycle of
 * two). The coupled step has one solution, the root of
 *     m (u − u_pred) / Δt² + k u + kc (u + V t₁)^p = 0,
 * found here independently by bisection. Checked: without backtracking the step does not
 * converge in 60 iterations (and cycles: the force is zero in about half of them); with it
 * every step converges to the bisection root (1e-9 m) and the loop counts its extra DEM
 * solves. The same model, reporting particles left out of its linearisation from a given
 * time on, checks that the loop counts those steps and passes the number on; reporting its K
 * scaled by a factor, it checks jacobian_check (cpl_jacobian_check.h): the exact derivative
 * passes to 1e-4 (the steps end within 1e-6 m of the contact boundary, where the central
 * difference of pen^0.5 itself misses by up to 7e-6), K × 0.7 misses by 0.3 (±1e-4) in every
 * check, and the check changes nothing in the run. With a convex law (p = 1.5, Hertz's) it
 * checks newton_estimate: fewer iterations, the same bisection roots. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <string.h>

#include "cpl_test_models.h"
#include "../../coupler/cpl_loop.h"

typedef struct node_model {
    double m_kg, k_n_m;
    double u0, v0, u, v;     /* start of step, current (z) */
} node_model;

typedef struct obstacle_model {
    double speed_m_s, kc, p;
    double dropped_from_s;   /* solves ending after this time report 2 dropped particles */
    double k_scale;          /* the K it reports: the exact one times this */
    long solves, zero_answers;
} obstacle_model;

static double overlap(const obstacle_model *o, double u, double t1)
{
    return u + o->speed_m_s * t1;
}

static int node_begin(void *ctx, const cpl_call *call, nc_error *err)
{
    (void)call; (void)err;
    node_model *n = ctx;
    n->u = n->u0;
    n->v = n->v0;
    return 0;
}

/* backward Euler with the linearised interface force about (jacobian_u) when given */
static int node_solve(void *ctx, const cpl_call *call, const double *f, const double *in1,
                      double *u_out, double *v_out, cpl_solve_info *info, nc_error *err)
{
    (void)in1; (void)info; (void)err;
    node_model *n = ctx;
    const double dt = call->dt_s, mt = n->m_kg / (dt * dt);
    double lhs = mt + n->k_n_m, rhs = mt * (n->u0 + dt * n->v0) + f[2];
    if (call->jacobian_in && call->jacobian_in->n_blocks == 1) {
        const double K = call->jacobian_in->stiffness[8];
        lhs += K;
        rhs += K * call->jacobian_u[2];
    }
    n->u = rhs / lhs;
    n->v = (n->u - n->u0) / dt;
    memset(u_out, 0, 3 * sizeof *u_out);
    memset(v_out, 0, 3 * sizeof *v_out);
    u_out[2] = n->u;
    v_out[2] = n->v;
    return 0;
}

static int node_accept(void *ctx, const cpl_call *call, nc_error *err)
{
    (void)call; (void)err;
    node_model *n = ctx;
    n->u0 = n->u;
    n->v0 = n->v;
    return 0;
}

static int obstacle_begin(void *ctx, const cpl_call *call, nc_error *err)
{
    (void)ctx; (void)call; (void)err;
    return 0;
}

static int obstacle_solve(void *ctx, const cpl_call *call, const double *u, const double *v,
                          double *f, double *out1, cpl_solve_info *info, nc_error *err)
{
    (void)v; (void)out1;
    obstacle_model *o = ctx;
    o->solves++;
    const double pen = overlap(o, u[2], call->time_s + call->dt_s);
    memset(f, 0, 3 * sizeof *f);
    double K[9] = {0};
    int32_t nodes[2] = {0, 0};
    if (pen > 0.0) {
        f[2] = -o->kc * pow(pen, o->p);
        K[8] = o->k_scale * o->kc * o->p * pow(pen, o->p - 1.0);
    } else {
        o->zero_answers++;
    }
    info->near_interface = 1;
    info->min_gap_m = -pen;
    info->contacts = pen > 0.0;
    if (call->jacobian_out && call->time_s + call->dt_s > o->dropped_from_s)
        info->jacobian_dropped = 2.0;
    if (call->jacobian_out)
        return cpl_jacobian_set(call->jacobian_out, pen > 0.0, nodes, K, NULL, err);
    return 0;
}

/* The coupled step's solution by bisection (the residual is increasing in u). */
static double step_root(const node_model *n, const obstacle_model *o, double t1, double dt)
{
    const double mt = n->m_kg / (dt * dt), pred = n->u0 + dt * n->v0;
    double lo = -o->speed_m_s * t1 - 1.0, hi = fmax(pred, 0.0) + 1.0;
    for (int i = 0; i < 200; i++) {
        double u = 0.5 * (lo + hi), pen = overlap(o, u, t1);
        double g = mt * (u - pred) + n->k_n_m * u + (pen > 0.0 ? o->kc * pow(pen, o->p) : 0.0);
        if (g > 0.0) hi = u; else lo = u;
    }
    return 0.5 * (lo + hi);
}

typedef struct run_log {
    node_model *node;
    obstacle_model *obstacle;
    long steps, converged;
    long dropped_steps;      /* step records with jacobian_dropped 2 */
    double max_error_m;
    node_model before;       /* committed state at the start of the current step */
    long misses_recorded;    /* iteration records with a jacobian_miss */
    double largest_miss_recorded;
    double u_end;            /* the node's displacement at the end of the run */
} run_log;

static int on_iteration(void *ctx, const cpl_iteration_record *rec, nc_error *err)
{
    (void)err;
    run_log *l = ctx;
    if (!isnan(rec->jacobian_miss)) {
        l->misses_recorded++;
        l->largest_miss_recorded = fmax(l->largest_miss_recorded, rec->jacobian_miss);
    }
    return 0;
}

static int on_step(void *ctx, const cpl_step_record *rec, nc_error *err)
{
    (void)err;
    run_log *l = ctx;
    l->steps++;
    l->converged += rec->converged;
    l->dropped_steps += rec->jacobian_dropped == 2;
    double root = step_root(&l->before, l->obstacle, rec->time_s, rec->dt_s);
    l->max_error_m = fmax(l->max_error_m, fabs(l->node->u - root));
    l->before.u0 = l->node->u;   /* the accepted state starts the next step */
    l->before.v0 = l->node->v;
    return 0;
}

/* What run_checked() adds to run(): the obstacle's K scale, the check interval, the contact
 * law's exponent (0: 0.5) and coupler.json newton_estimate, and what the check found and the
 * run counted. */
typedef struct check_case {
    double k_scale;
    int interval;
    double p, newton_estimate;
    cpl_jacobian_check found;
    long iterations, estimate_steps;
} check_case;

static void run_checked(int backtracking, double dropped_from_s, run_log *log,
                        long *backtracks, long *dropped_steps, check_case *check)
{
    /* a 0.16 kg net node on a 1e5 N/m support, an obstacle at 10 m/s, kc pen^0.5 */
    node_model node = {.m_kg = 0.16, .k_n_m = 1e5};
    obstacle_model obstacle = {.speed_m_s = 10.0, .kc = 3e6,
                               .p = check && check->p > 0.0 ? check->p : 0.5,
                               .dropped_from_s = dropped_from_s,
                               .k_scale = check ? check->k_scale : 1.0};
    cpl_participant fem = {.name = "fem", .ctx = &node, .begin_step = node_begin,
                           .solve = node_solve, .accept = node_accept, .can_jacobian = 1};
    cpl_participant dem = {.name = "dem", .ctx = &obstacle, .begin_step = obstacle_begin,
                           .solve = obstacle_solve, .accept = obstacle_begin,
                           .can_jacobian = 1};
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 1e-3, 5e-3);
    nc_error err = {0};
    assert_int_equal(cpl_relax_settings_select(&s.relax, "constant", &err), 0);
    s.relax.alpha = 1.0;   /* the FEM's answer is the Newton iterate */
    s.max_iterations = 60;
    s.dt_min_s = s.dt_s;   /* no step rejection: the iteration itself is under test */
    s.contact_backtracking = backtracking;
    s.jacobian_check_interval = check ? check->interval : 0;
    s.newton_estimate = check ? check->newton_estimate : 0.0;
    memset(log, 0, sizeof *log);
    log->node = &node;
    log->obstacle = &obstacle;
    log->before = node;
    cpl_observer obs = {.ctx = log, .on_step = on_step, .on_iteration = on_iteration};
    cpl_loop *loop = NULL;
    assert_int_equal(cpl_loop_create(&loop, &s, 1, NULL, NULL, &err), 0);
    cpl_failure where;
    int rc = cpl_loop_run(loop, &fem, &dem, &obs, NULL, &where, &err);
    assert_int_equal(rc, 0);
    *backtracks = cpl_loop_timing(loop)->backtracks;
    *dropped_steps = cpl_loop_timing(loop)->jacobian_dropped_steps;
    if (check) {
        check->found = *cpl_loop_jacobian_check(loop);
        check->iterations = cpl_loop_timing(loop)->iterations;
        check->estimate_steps = cpl_loop_timing(loop)->estimate_steps;
    }
    log->u_end = node.u;
    cpl_loop_free(loop);
    log->obstacle = NULL;
    log->node = NULL;
    print_message("backtracking %d: %ld of %ld steps converged, %ld DEM solves, %ld without "
                  "contact, %ld backtracks, largest error %.3g m\n", backtracking,
                  log->converged, log->steps, obstacle.solves, obstacle.zero_answers,
                  *backtracks, log->max_error_m);
    if (backtracking == 0) {
        assert_true(obstacle.zero_answers > obstacle.solves / 4);   /* the cycle */
    }
}

static void run(int backtracking, double dropped_from_s, run_log *log, long *backtracks,
                long *dropped_steps)
{
    run_checked(backtracking, dropped_from_s, log, backtracks, dropped_steps, NULL);
}

static void test_without_backtracking_the_iteration_cycles(void **state)
{
    (void)state;
    run_log log;
    long backtracks = -1, dropped = -1;
    run(0, INFINITY, &log, &backtracks, &dropped);
    assert_int_equal(dropped, 0);
    assert_int_equal(backtracks, 0);
    assert_int_equal(log.steps, 5);
    assert_true(log.converged < log.steps);
}

static void test_backtracking_converges_to_the_step_solution(void **state)
{
    (void)state;
    run_log log;
    long backtracks = 0, dropped = -1;
    run(4, INFINITY, &log, &backtracks, &dropped);
    assert_int_equal(dropped, 0);
    assert_int_equal(log.steps, 5);
    assert_int_equal(log.converged, log.steps);
    assert_true(backtracks > 0);
    assert_below(log.max_error_m, 1e-9);
}

/* 5 steps of 1e-3 s; the solves of steps 3, 4 and 5 (ending after 2.5e-3 s) drop particles */
static void test_dropped_particles_are_counted(void **state)
{
    (void)state;
    run_log log;
    long backtracks = 0, dropped = -1;
    run(4, 2.5e-3, &log, &backtracks, &dropped);
    assert_int_equal(log.steps, 5);
    assert_int_equal(dropped, 3);
    assert_int_equal(log.dropped_steps, 3);
}

/* the exact K passes the check on every step, and the check changes nothing in the run */
static void test_jacobian_check_passes_the_exact_derivative(void **state)
{
    (void)state;
    run_log plain, checked;
    long backtracks = 0, dropped = 0;
    run(4, INFINITY, &plain, &backtracks, &dropped);
    check_case check = {.k_scale = 1.0, .interval = 1};
    run_checked(4, INFINITY, &checked, &backtracks, &dropped, &check);
    print_message("exact K: %ld checks (%ld DEM solves), largest miss %.3g\n",
                  check.found.checks, check.found.solves, check.found.worst);
    assert_true(check.found.checks >= checked.steps);
    assert_int_equal(check.found.solves, 2 * check.found.checks);
    assert_int_equal(check.found.missed, 0);
    assert_below(check.found.worst, 1e-4);
    assert_int_equal(checked.misses_recorded, check.found.checks);
    assert_near(checked.largest_miss_recorded, check.found.worst, 0.0);
    assert_int_equal(checked.converged, checked.steps);
    assert_true(checked.u_end == plain.u_end);
    /* every second step only: step indices 0, 2, 4 */
    check_case sparse = {.k_scale = 1.0, .interval = 2};
    run_checked(4, INFINITY, &checked, &backtracks, &dropped, &sparse);
    assert_true(sparse.found.checks > 0 && sparse.found.checks < check.found.checks);
}

/* a K 30 % too small: every check reports a miss of 0.3 = |D − 0.7 D| / |D| */
static void test_jacobian_check_finds_a_wrong_derivative(void **state)
{
    (void)state;
    run_log log;
    long backtracks = 0, dropped = 0;
    check_case check = {.k_scale = 0.7, .interval = 1};
    run_checked(4, INFINITY, &log, &backtracks, &dropped, &check);
    print_message("K x 0.7: %ld checks, %ld above %g, largest miss %.6f at step %ld iteration "
                  "%d\n", check.found.checks, check.found.missed, CPL_JACOBIAN_CHECK_WARN,
                  check.found.worst, check.found.worst_step, check.found.worst_iteration);
    assert_true(check.found.checks > 0);
    assert_int_equal(check.found.missed, check.found.checks);
    assert_near(check.found.worst, 0.3, 1e-4);
    assert_true(check.found.worst_iteration >= 1);
    assert_near(log.largest_miss_recorded, check.found.worst, 0.0);
}

/* newton_estimate on a Hertz law (p = 1.5, convex: Newton converges quadratically once in
 * contact): a step is accepted after the iteration whose residual contracted by at most 0.1
 * when the error estimate of the structure's answer meets the tolerance, which saves the
 * iteration that would only confirm it; every step still ends on the bisection root within
 * what the tolerance allows (1e-10 on the velocity residual: 1e-13 m here, Δt 1e-3 s). */
static void test_newton_estimate_saves_the_confirming_iteration(void **state)
{
    (void)state;
    run_log plain, estimated;
    long backtracks = 0, dropped = 0;
    check_case off = {.k_scale = 1.0, .p = 1.5};
    check_case on = {.k_scale = 1.0, .p = 1.5, .newton_estimate = 0.1};
    run_checked(4, INFINITY, &plain, &backtracks, &dropped, &off);
    run_checked(4, INFINITY, &estimated, &backtracks, &dropped, &on);
    print_message("Hertz: %ld interface iterations with eq. (35), %ld with newton_estimate 0.1 "
                  "(%ld of %ld steps by the estimate); largest error %.3g m and %.3g m\n",
                  off.iterations, on.iterations, on.estimate_steps, estimated.steps,
                  plain.max_error_m, estimated.max_error_m);
    assert_int_equal(plain.converged, plain.steps);
    assert_int_equal(estimated.converged, estimated.steps);
    assert_int_equal(off.estimate_steps, 0);
    assert_true(on.estimate_steps > 0);
    assert_true(on.iterations <= off.iterations - on.estimate_steps);
    assert_below(plain.max_error_m, 1e-12);
    assert_below(estimated.max_error_m, 1e-12);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_without_backtracking_the_iteration_cycles),
        cmocka_unit_test(test_backtracking_converges_to_the_step_solution),
        cmocka_unit_test(test_dropped_particles_are_counted),
        cmocka_unit_test(test_jacobian_check_passes_the_exact_derivative),
        cmocka_unit_test(test_jacobian_check_finds_a_wrong_derivative),
        cmocka_unit_test(test_newton_estimate_saves_the_confirming_iteration),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
