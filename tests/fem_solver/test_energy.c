/* test_energy — the FEM's step energy balance (fem_analysis_step_energy), which the coupled
 * FEM reports with each SOLVE reply: on the taut string (nearly linear at the small
 * amplitudes used) Newmark beta = 1/4, gamma = 1/2 without damping closes its balance
 * load work + coupling work = Δ(kinetic + strain), so the numerical term vanishes, with a
 * coupling force that changes every step ("end_of_step": the trapezoid of the start and end
 * force; "step_constant": the step's force); with mass- or stiffness-proportional Rayleigh
 * damping the Rayleigh term is >= 0 every step and (mass-proportional, exact for the
 * trapezoidal rule) the numerical term still vanishes; generalized-alpha's numerical
 * damping shows up as a positive numerical term. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../../fem_solver/fem_analysis.h"
#include "fem_test_util.h"

/* String: L = 1 m, A = 1e-4 m^2, rho = 1000 kg/m^3, tension 100 N (test_dynamic.c). */
static void string_model(fem_model *m, fem_integrator integ, double tau, double kappa,
                         int step_constant)
{
    fem_test_line(m, 20, 1.0, 1e9, 1e-4, 1000.0, 100.0 / 1e-4, FEM_TRUSS, 1);
    m->settings.type = FEM_DYNAMIC;
    m->settings.integrator = integ;
    m->settings.rho_inf = 0.5;
    m->settings.residual_tol_n = 1e-13;
    m->settings.displacement_tol_m = 1e-15;
    m->settings.coupling_load_constant = step_constant;
    m->tau_per_s = tau;
    m->kappa_s = kappa;
    nc_error err;
    assert_int_equal(fem_model_finalize(m, &err), 0);
}

typedef struct balance {
    double input_j;         /* largest kinetic + strain energy */
    double coupling_j;      /* Σ coupling work */
    double numerical_j;     /* Σ numerical */
    double max_abs_numerical_j;
    double rayleigh_j;      /* Σ Rayleigh */
    double min_rayleigh_j;  /* smallest Rayleigh term of a step */
    double closure_j;       /* max |E_n - E_0 - Σ (work - dissipation)| */
} balance;

/* 400 steps of 1e-4 s from a plucked first mode (amplitude 1e-5 m) under a transverse
 * coupling force at the middle node that changes every step. */
static void run(fem_integrator integ, double tau, double kappa, int step_constant, balance *b)
{
    fem_model m;
    string_model(&m, integ, tau, kappa, step_constant);
    fem_analysis s;
    nc_error err;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    for (int i = 0; i < m.n_nodes; i++) s.cur.u[3 * i + 2] = 1e-5 * sin(M_PI * m.X[3 * i]);
    assert_int_equal(fem_analysis_initial_acceleration(&s, &err), 0);
    memset(b, 0, sizeof *b);
    b->min_rayleigh_j = INFINITY;
    const double E0 = fem_analysis_energy(&s, NULL, NULL);
    double sum = 0;
    for (int k = 0; k < 400; k++) {
        s.f_coupling[3 * 10 + 2] = 1e-3 * sin(0.05 * k) + (k % 7 == 0 ? 2e-4 : 0.0);
        s.f_coupling[3 * 7 + 1] = k < 200 ? 5e-4 : 0.0;
        if (fem_analysis_step(&s, 1e-4, &err)) fail_msg("%s", err.message);
        fem_step_energy e;
        assert_int_equal(fem_analysis_step_energy(&s, 1, &e), 0);
        b->input_j = fmax(b->input_j, e.kinetic_j + e.strain_j);
        b->coupling_j += e.coupling_work_j;
        b->numerical_j += e.numerical_j;
        b->max_abs_numerical_j = fmax(b->max_abs_numerical_j, fabs(e.numerical_j));
        b->rayleigh_j += e.rayleigh_j;
        b->min_rayleigh_j = fmin(b->min_rayleigh_j, e.rayleigh_j);
        assert_near(e.load_work_j, 0.0, 0.0);              /* no self-weight, no point loads */
        sum += e.load_work_j + e.coupling_work_j - e.rayleigh_j - e.numerical_j;
        double kin, strain;
        fem_analysis_energy(&s, &kin, &strain);
        assert_near_rel(e.kinetic_j, kin, 1e-14);
        b->closure_j = fmax(b->closure_j, fabs(kin + strain - E0 - sum));
    }
    fem_analysis_free(&s);
    fem_model_free(&m);
}

/* Newmark (1/4, 1/2), no damping: the accumulated numerical term is below 1e-6 of the energy
 * (observed ~1e-7) and that of any single step below 1e-5 (observed 2e-6: the trapezoidal
 * rule is exact for a linear system only; the string's strain energy is a small difference
 * of prestressed terms and the truss is geometrically nonlinear), for both coupling-load
 * forms; the coupling force did real work (> 1 % of the energy); the reported terms add up
 * to the energy change to round-off. */
static void test_newmark_closes(void **state)
{
    (void)state;
    for (int constant = 0; constant < 2; constant++) {
        balance b;
        run(FEM_NEWMARK, 0.0, 0.0, constant, &b);
        print_message("newmark, %s: energy %.4e J, coupling work %.4e J, numerical %.3e J "
                      "(largest step %.3e J), closure %.3e J\n",
                      constant ? "step_constant" : "end_of_step", b.input_j, b.coupling_j,
                      b.numerical_j, b.max_abs_numerical_j, b.closure_j);
        assert_below(0.01 * b.input_j, fabs(b.coupling_j));
        assert_below(fabs(b.numerical_j), 1e-6 * b.input_j);
        assert_below(b.max_abs_numerical_j, 1e-5 * b.input_j);
        assert_below(b.closure_j, 1e-12 * b.input_j);
        assert_near(b.rayleigh_j, 0.0, 0.0);
    }
}

/* Rayleigh damping: mass-proportional (tau = 5 /s) and stiffness-proportional (kappa =
 * 1e-4 s): the Rayleigh term is >= 0 in every step and removes a visible share of the
 * energy; for tau alone Newmark's numerical term stays below 1e-6 of the energy (the
 * trapezoidal rule dissipates exactly dt v_m·C v_m), with kappa (K_T taken at the start of
 * the step) below 1e-3 of the Rayleigh dissipation. */
static void test_rayleigh_nonnegative(void **state)
{
    (void)state;
    balance b;
    run(FEM_NEWMARK, 5.0, 0.0, 0, &b);
    print_message("tau: rayleigh %.4e J (smallest step %.3e J), numerical %.3e J of %.4e J\n",
                  b.rayleigh_j, b.min_rayleigh_j, b.numerical_j, b.input_j);
    assert_true(b.min_rayleigh_j >= 0.0);
    assert_below(0.01 * b.input_j, b.rayleigh_j);
    assert_below(fabs(b.numerical_j), 1e-6 * b.input_j);
    run(FEM_NEWMARK, 0.0, 1e-4, 0, &b);
    print_message("kappa: rayleigh %.4e J (smallest step %.3e J), numerical %.3e J of %.4e J\n",
                  b.rayleigh_j, b.min_rayleigh_j, b.numerical_j, b.input_j);
    assert_true(b.min_rayleigh_j >= 0.0);
    assert_below(0.01 * b.input_j, b.rayleigh_j);
    assert_below(fabs(b.numerical_j), 1e-3 * b.rayleigh_j);
}

/* Generalized-alpha (rho_inf = 0.5) damps numerically: its numerical term is positive. */
static void test_alpha_method_dissipates(void **state)
{
    (void)state;
    balance b;
    run(FEM_GENERALIZED_ALPHA, 0.0, 0.0, 0, &b);
    print_message("generalized-alpha: numerical %.4e J of %.4e J, closure %.3e J\n",
                  b.numerical_j, b.input_j, b.closure_j);
    assert_below(0.0, b.numerical_j);
    assert_below(b.closure_j, 1e-12 * b.input_j);
}

/* Stiffness-proportional damping on a net whose ropes go slack: a 9 x 9 net (1 m, fixed
 * edges, E 1e8 Pa, A 1e-5 m^2, prestress 1e5 Pa, self-weight) pulled down at its centre by
 * 200 N for 20 ms and released, 200 steps of 1 ms with Newmark (1/4, 1/2) and kappa = 1e-3 s
 * (a damping ratio kappa w / 2 of 0.9 at the element's axial frequency, ~1800 rad/s).
 * C_K = kappa K_T(u_n) is fixed over each step, so Newton's tangent is exact: every step
 * converges in at most 6 iterations (observed 5; a C_K(u) without its derivative in the
 * tangent took 13), some ropes are slack, the Rayleigh term is >= 0 in every step, and the
 * integrator term, which for the trapezoidal rule is only the elements' nonlinearity over a
 * step, stays below 5 % of the Rayleigh dissipation (observed +3.3 %; with C_K(u) it was
 * -10 %: energy created). */
static void test_stiffness_damping_slack_net(void **state)
{
    (void)state;
    fem_model m;
    nc_error err;
    fem_element_set set = {"net", 1e8, 1e-5, 7850, 1e5, FEM_CABLE, 0.0};
    if (!fem_test_net(&m, 9, &set, &err)) fail_msg("%s", err.message);
    m.self_weight = 1;
    m.kappa_s = 1e-3;
    m.settings.type = FEM_DYNAMIC;
    m.settings.integrator = FEM_NEWMARK;
    m.settings.max_iterations = 20;
    assert_int_equal(fem_model_finalize(&m, &err), 0);
    fem_analysis s;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(&s, &err), 0);
    double rayleigh = 0, numerical = 0, min_rayleigh = INFINITY, energy_max = 0;
    int max_iterations = 0, max_slack = 0;
    for (int k = 0; k < 200; k++) {
        s.f_coupling[3 * 40 + 2] = k < 20 ? -200.0 : 0.0;
        if (fem_analysis_step(&s, 1e-3, &err)) fail_msg("step %d: %s", k, err.message);
        max_iterations = s.stats.iterations > max_iterations ? s.stats.iterations : max_iterations;
        max_slack = s.stats.slack_elements > max_slack ? s.stats.slack_elements : max_slack;
        fem_step_energy e;
        assert_int_equal(fem_analysis_step_energy(&s, 1, &e), 0);
        rayleigh += e.rayleigh_j;
        numerical += e.numerical_j;
        min_rayleigh = fmin(min_rayleigh, e.rayleigh_j);
        energy_max = fmax(energy_max, e.kinetic_j + e.strain_j);
    }
    print_message("slack net, kappa: at most %d Newton iterations, %d slack elements, rayleigh "
                  "%.4e J (smallest step %.3e J), numerical %.3e J, largest energy %.4e J\n",
                  max_iterations, max_slack, rayleigh, min_rayleigh, numerical, energy_max);
    assert_true(max_iterations <= 6);
    assert_true(max_slack > 0);
    assert_true(min_rayleigh >= 0.0);
    assert_below(0.1 * energy_max, rayleigh);
    assert_below(fabs(numerical), 0.05 * rayleigh);
    fem_analysis_free(&s);
    fem_model_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_newmark_closes),
        cmocka_unit_test(test_rayleigh_nonnegative),
        cmocka_unit_test(test_alpha_method_dissipates),
        cmocka_unit_test(test_stiffness_damping_slack_net),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
