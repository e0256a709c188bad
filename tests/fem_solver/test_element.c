/* test_element — the cable/truss element alone and in the smallest models: axial bar
 * against E A / L, tangent against finite differences of the internal force, slackening,
 * mass matrix totals. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <string.h>

#include "../../fem_solver/fem_analysis.h"
#include "../../fem_solver/fem_element_cable.h"
#include "fem_test_util.h"

/* internal force vector [f_k, f_l] for nodal positions xk, xl */
static void element_force(const double xk[3], const double xl[3], double L0, double EA,
                          double AS, int cable, double f[6])
{
    double d[3] = {xl[0] - xk[0], xl[1] - xk[1], xl[2] - xk[2]}, fl[3], Kb[9];
    fem_cable_response(d, L0, EA, AS, cable, fl, Kb, NULL);
    for (int c = 0; c < 3; c++) {
        f[c] = -fl[c];
        f[3 + c] = fl[c];
    }
}

/* Single bar along x, node 0 fixed, axial pull P at node 1: for a small load the
 * elongation is P L / (E A); the total-Lagrangian bar is exactly
 * P = E A (l^2 - L^2)/(2 L^2) * l / L, checked to 1e-10 relative for a large load. */
static void test_axial_bar(void **state)
{
    (void)state;
    const double L = 2.0, E = 2.1e11, A = 1e-4, P_small = 10.0, P_large = 2e6;
    for (int pass = 0; pass < 2; pass++) {
        double P = pass ? P_large : P_small;
        fem_model m;
        fem_test_line(&m, 1, L, E, A, 0.0, 0.0, FEM_TRUSS, 0);
        for (int c = 0; c < 3; c++) m.fixed[c] = 1;
        m.fixed[4] = m.fixed[5] = 1;   /* node 1 moves along x only */
        m.f_point[3] = P;
        m.settings.type = FEM_STATIC;
        nc_error err;
        assert_int_equal(fem_model_finalize(&m, &err), 0);
        fem_analysis s;
        assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
        assert_int_equal(fem_analysis_static(&s, 1.0, &err), 0);
        double u = s.cur.u[3];
        if (!pass) {
            /* strain 5e-7: the nonlinear terms are ~1e-6 relative; tolerance 1e-5 */
            assert_near_rel(u, P * L / (E * A), 1e-5);
        } else {
            double l = L + u;
            double P_exact = E * A * (l * l - L * L) / (2 * L * L) * l / L;
            assert_near_rel(P_exact, P, 1e-10);
            assert_near_rel(s.axial[0], P, 1e-8);
        }
        fem_analysis_free(&s);
        fem_model_free(&m);
    }
}

/* Consistent tangent (eq. (9)) against central differences of the internal force (eq. (8))
 * for taut cables and a compressed truss at random chords: relative error < 1e-6
 * (central differences with h = 1e-6 L are accurate to ~1e-10 here). */
static void test_tangent_fd(void **state)
{
    (void)state;
    unsigned seed = 12345;
    for (int trial = 0; trial < 20; trial++) {
        double xk[3], xl[3], EA = 1e5, AS = 50.0 * (trial % 3 == 2 ? -1 : 1);
        int cable = trial % 3 != 2;
        double L0 = cable ? 1.0 : 1.6;   /* taut cables; compressed truss */
        for (int c = 0; c < 3; c++) {
            seed = seed * 1103515245u + 12345u;
            xk[c] = 0.3 * ((seed >> 8) % 1000 / 1000.0 - 0.5);
            seed = seed * 1103515245u + 12345u;
            xl[c] = (c == 0 ? 1.35 : 0.0) + 0.3 * ((seed >> 8) % 1000 / 1000.0 - 0.5);
        }
        double d[3] = {xl[0] - xk[0], xl[1] - xk[1], xl[2] - xk[2]}, fl[3], Kb[9];
        int slack;
        fem_cable_response(d, L0, EA, AS, cable, fl, Kb, &slack);
        assert_int_equal(slack, 0);
        double K[36];
        for (int a = 0; a < 6; a++)
            for (int b = 0; b < 6; b++)
                K[6 * a + b] = Kb[3 * (a % 3) + b % 3] * (((a < 3) == (b < 3)) ? 1 : -1);
        double h = 1e-6 * L0, kmax = 0, errmax = 0;
        for (int b = 0; b < 6; b++) {
            double xp[6], xm[6], fp[6], fm[6];
            memcpy(xp, xk, sizeof xk); memcpy(xp + 3, xl, sizeof xl);
            memcpy(xm, xp, sizeof xp);
            xp[b] += h;
            xm[b] -= h;
            element_force(xp, xp + 3, L0, EA, AS, cable, fp);
            element_force(xm, xm + 3, L0, EA, AS, cable, fm);
            for (int a = 0; a < 6; a++) {
                /* K = d f_int / d x */
                double fd = (fp[a] - fm[a]) / (2 * h);
                errmax = fmax(errmax, fabs(fd - K[6 * a + b]));
                kmax = fmax(kmax, fabs(K[6 * a + b]));
            }
        }
        assert_below(errmax, 1e-6 * kmax);
    }
}

/* A cable shorter than its stress-free length (S_tot < 0) carries nothing and has no
 * stiffness; the same element as a truss keeps the compressive force N = A S_tot l / L. */
static void test_slack(void **state)
{
    (void)state;
    double d[3] = {0.9, 0, 0}, f[3], Kb[9];
    int slack = 0;
    double N = fem_cable_response(d, 1.0, 1e5, 10.0, 1, f, Kb, &slack);
    assert_int_equal(slack, 1);
    assert_near(N, 0.0, 0.0);
    for (int i = 0; i < 3; i++) assert_near(f[i], 0.0, 0.0);
    for (int i = 0; i < 9; i++) assert_near(Kb[i], 0.0, 0.0);
    N = fem_cable_response(d, 1.0, 1e5, 10.0, 0, f, Kb, &slack);
    assert_int_equal(slack, 0);
    double expected = (1e5 * (0.81 - 1.0) / 2.0 + 10.0) * 0.9;   /* A S_tot l / L */
    assert_near_rel(N, expected, 1e-9);
    assert_below(N, 0.0);
    assert_below(f[0], 0.0);
    /* prestress alone keeps a cable taut down to E = -S_pre/E_mod: at l = L it is taut */
    d[0] = 1.0;
    N = fem_cable_response(d, 1.0, 1e5, 10.0, 1, f, Kb, &slack);
    assert_int_equal(slack, 0);
    assert_near(N, 10.0, 1e-12);

    /* in a model: a 2-element cable whose elements are slack (negative prestress) leaves
     * the middle node unheld; the static solve must fail naming node 1 */
    fem_model m;
    fem_test_line(&m, 2, 2.0, 1e5, 1e-4, 0.0, -1e3, FEM_CABLE, 1);
    m.f_point[5] = -1.0;
    m.settings.type = FEM_STATIC;
    nc_error err;
    assert_int_equal(fem_model_finalize(&m, &err), 0);
    fem_analysis s;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    assert_int_equal(fem_analysis_static(&s, 1.0, &err), -1);
    assert_non_null(strstr(err.message, "node 1"));
    fem_analysis_free(&s);
    fem_model_free(&m);
}

/* Mass (eq. (11)): consistent and lumped both carry the element mass rho A L per direction:
 * sum of the 2x2 coefficients = rho A L. */
static void test_mass(void **state)
{
    (void)state;
    double m11, m12;
    fem_cable_mass(7850 * 1e-4, 2.0, 0, &m11, &m12);
    assert_near(2 * m11 + 2 * m12, 7850 * 1e-4 * 2.0, 1e-12);
    assert_near(m11, 2 * m12, 1e-15);
    fem_cable_mass(7850 * 1e-4, 2.0, 1, &m11, &m12);
    assert_near(2 * m11, 7850 * 1e-4 * 2.0, 1e-12);
    assert_near(m12, 0.0, 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_axial_bar),
        cmocka_unit_test(test_tangent_fd),
        cmocka_unit_test(test_slack),
        cmocka_unit_test(test_mass),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
