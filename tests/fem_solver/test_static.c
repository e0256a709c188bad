/* test_static — static Newton against independent solutions: the paper's 3-element
 * prestressed cable (section 7.2) under two symmetric inner point loads vs its closed-form
 * large-deflection equilibrium, the LU path for a compressed truss, and the singular-matrix
 * message naming the node. */
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

/* Closed form of the symmetric 3-element cable (nodes at x = 0, 1, 2, 3, L = 1 each, ends
 * fixed, load P downwards at nodes 1 and 2). By symmetry node 1 sits at (1 + a, 0, -w),
 * node 2 at (2 - a, 0, -w): the inner element stays horizontal, the outer ones rotate.
 * With A S(l) = E A (l^2 - 1)/2 + A S_pre (eq. (10), L = 1) node 1 balances
 *   x: -A S_o (1 + a) + A S_i (1 - 2a) = 0,   z: A S_o w - P = 0,
 * l_o = sqrt((1+a)^2 + w^2), l_i = 1 - 2a. For a given w the x equation is monotone in a
 * (bisection), and then the z equation is monotone in w (outer bisection). */
static double AS_of(double l, double EA, double AS_pre)
{
    return EA * (l * l - 1.0) / 2.0 + AS_pre;
}

static double solve_a(double w, double EA, double AS_pre)
{
    double lo = -0.45, hi = 0.45;
    for (int i = 0; i < 200; i++) {
        double a = 0.5 * (lo + hi);
        double lo_len = sqrt((1 + a) * (1 + a) + w * w), li = 1 - 2 * a;
        double g = -AS_of(lo_len, EA, AS_pre) * (1 + a) + AS_of(li, EA, AS_pre) * li;
        if (g > 0) lo = a; else hi = a;   /* g decreases with a */
    }
    return 0.5 * (lo + hi);
}

static void closed_form(double P, double EA, double AS_pre, double *a_out, double *w_out)
{
    double lo = 0.0, hi = 2.0;
    for (int i = 0; i < 200; i++) {
        double w = 0.5 * (lo + hi), a = solve_a(w, EA, AS_pre);
        double h = AS_of(sqrt((1 + a) * (1 + a) + w * w), EA, AS_pre) * w - P;
        if (h < 0) lo = w; else hi = w;
    }
    *w_out = 0.5 * (lo + hi);
    *a_out = solve_a(*w_out, EA, AS_pre);
}

/* Paper 7.2 cable (E = 1e9, A = 1.26e-4, S_pre = 1e6) with the sphere weight
 * 4/3 pi R^3 rho g (R = 0.12, rho = 3.5e4) split onto the two inner nodes, and a 10x
 * larger load; FEM vs closed form: |dw|, |da| < 1e-9 m (both are solved to ~1e-12). */
static void test_three_element_cable(void **state)
{
    (void)state;
    const double E = 1e9, A = 1.26e-4, S_pre = 1e6;
    const double weight = 4.0 / 3.0 * M_PI * pow(0.12, 3) * 3.5e4 * 9.81;
    for (int pass = 0; pass < 2; pass++) {
        double P = 0.5 * weight * (pass ? 10.0 : 1.0);
        fem_model m;
        fem_test_line(&m, 3, 3.0, E, A, 7850, S_pre, FEM_CABLE, 1);
        m.f_point[3 * 1 + 2] = -P;
        m.f_point[3 * 2 + 2] = -P;
        m.settings.type = FEM_STATIC;
        m.settings.residual_tol_n = 1e-9;
        nc_error err;
        assert_int_equal(fem_model_finalize(&m, &err), 0);
        fem_analysis s;
        assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
        int steps = 5;
        for (int k = 1; k <= steps; k++) {
            int rc = fem_analysis_static(&s, (double)k / steps, &err);
            if (rc) fail_msg("%s", err.message);
        }
        double a, w;
        closed_form(P, E * A, S_pre * A, &a, &w);
        double w_fem = -s.cur.u[3 * 1 + 2], a_fem = s.cur.u[3 * 1 + 0];
        print_message("P = %.4f N: closed form w = %.12f a = %.12f, FEM w = %.12f a = %.12f\n",
                      P, w, a, w_fem, a_fem);
        assert_near(w_fem, w, 1e-9);
        assert_near(a_fem, a, 1e-9);
        /* symmetry: node 2 mirrors node 1, the inner element stays horizontal */
        assert_near(s.cur.u[3 * 2 + 0], -a_fem, 1e-12);
        assert_near(s.cur.u[3 * 2 + 2], s.cur.u[3 * 1 + 2], 1e-12);
        fem_analysis_free(&s);
        fem_model_free(&m);
    }
}

/* The Newton iteration's rounding floor. The three-element cable (as above, 10x load)
 * carries element forces of about 1e3 N, whose rounding leaves a residual near 1e-11 N that
 * no increment can reduce (the increments fall below an ulp of the coordinates). With a
 * tolerance of 1e-13 N that floor is within 1e3 of it: the solve is converged at the floor
 * and counted, with the closed-form answer (1e-9 m); with 1e-18 N it is far above: the solve
 * still fails with a Newton message, so the rule does not pass an arbitrary residual. */
static void test_rounding_floor(void **state)
{
    (void)state;
    const double E = 1e9, A = 1.26e-4, S_pre = 1e6;
    const double P = 5.0 * 4.0 / 3.0 * M_PI * pow(0.12, 3) * 3.5e4 * 9.81;
    const double tols[2] = {1e-13, 1e-18};
    for (int pass = 0; pass < 2; pass++) {
        fem_model m;
        fem_test_line(&m, 3, 3.0, E, A, 7850, S_pre, FEM_CABLE, 1);
        m.f_point[3 * 1 + 2] = -P;
        m.f_point[3 * 2 + 2] = -P;
        m.settings.type = FEM_STATIC;
        m.settings.residual_tol_n = tols[pass];
        m.settings.relative_tol = 0.0;
        nc_error err;
        assert_int_equal(fem_model_finalize(&m, &err), 0);
        fem_analysis s;
        assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
        int rc = 0;
        for (int k = 1; k <= 5 && rc == 0; k++) rc = fem_analysis_static(&s, k / 5.0, &err);
        print_message("tolerance %g N: rc %d, residual %.3g N, %ld solves at the floor%s%s\n",
                      tols[pass], rc, s.stats.residual_norm, s.stats.roundoff_converged,
                      rc ? ": " : "", rc ? err.message : "");
        if (pass == 0) {
            assert_int_equal(rc, 0);
            assert_true(s.stats.roundoff_converged > 0);
            assert_below(s.stats.residual_norm, 1e3 * tols[pass]);
            double a, w;
            closed_form(P, E * A, S_pre * A, &a, &w);
            assert_near(-s.cur.u[3 * 1 + 2], w, 1e-9);
            assert_near(s.cur.u[3 * 1 + 0], a, 1e-9);
        } else {
            assert_int_not_equal(rc, 0);
            assert_non_null(strstr(err.message, "Newton did not converge"));
        }
        fem_analysis_free(&s);
        fem_model_free(&m);
    }
}

/* A straight 2-element truss under axial compression: the geometric stiffness of the
 * transverse dofs is negative: CHOLMOD's LDL^T factorises it as it is; its supernodal
 * LL^T reports "not positive definite" and UMFPACK LU solves. The answer is the straight compressed bar: P = -A S(l) l / L per element, with
 * l from the stiffer 1-D relation; checked to 1e-9 relative in force. */
static void test_compressed_truss_lu(void **state)
{
    (void)state;
    for (int mode = 1; mode <= 2; mode++) {
    fem_model m;
    const double EA = 1e6, P = 1e3;
    /* a small compressive prestress makes the transverse stiffness negative (not zero)
     * from the first iteration */
    const double AS = -0.1;
    fem_test_line(&m, 2, 2.0, 1e10, 1e-4, 0.0, AS / 1e-4, FEM_TRUSS, 0);
    for (int c = 0; c < 3; c++) m.fixed[c] = 1;
    m.fixed[3 * 2 + 1] = m.fixed[3 * 2 + 2] = 1;   /* end moves along x only */
    m.f_point[3 * 2] = -P;
    m.settings.type = FEM_STATIC;
    m.settings.factorization = mode;   /* 1: LDL^T copes; 2: LL^T fails, LU takes over */
    nc_error err;
    assert_int_equal(fem_model_finalize(&m, &err), 0);
    fem_analysis s;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    if (fem_analysis_static(&s, 1.0, &err)) fail_msg("%s", err.message);
    if (mode == 2) assert_true(s.stats.lu_factorizations > 0);
    else assert_true(s.stats.lu_factorizations == 0);
    for (int e = 0; e < 2; e++) assert_near(s.axial[e], -P, 1e-9 * P);
    double l = 1.0 + s.cur.u[3] - s.cur.u[0];
    assert_near((EA * (l * l - 1) / 2 + AS) * l, -P, 1e-9 * P);
    fem_analysis_free(&s);
    fem_model_free(&m);
    }
}

/* A flat net without prestress has no out-of-plane stiffness at the reference state:
 * the static solve must fail with a message naming a node and the z dof. */
static void test_flat_net_singular(void **state)
{
    (void)state;
    fem_model m;
    nc_error err;
    fem_element_set set = {"net", 1e6, 1e-4, 1000, 0.0, FEM_CABLE, 0.0};
    const fem_node_set *b = fem_test_net(&m, 5, &set, &err);
    if (!b) fail_msg("%s", err.message);
    assert_int_equal(b->count, 16);
    m.f_point[3 * 12 + 2] = -1.0;
    m.settings.type = FEM_STATIC;
    assert_int_equal(fem_model_finalize(&m, &err), 0);
    assert_int_equal(m.n_elements, 40);
    fem_analysis s;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    assert_int_equal(fem_analysis_static(&s, 1.0, &err), -1);
    print_message("expected error: %s\n", err.message);
    assert_non_null(strstr(err.message, "node "));
    assert_non_null(strstr(err.message, "dof z"));
    fem_analysis_free(&s);
    fem_model_free(&m);
}

/* A Newton failure says where: a prestressed 2-element cable (ends fixed, so node 1 is the
 * only free node) under a transverse load far beyond what one Newton iteration can balance
 * fails, and the message names node 1 and dof z (the load's direction: by symmetry the two
 * elements' x forces cancel) with the largest residual, which is the z residual itself. */
static void test_newton_failure_names_dof(void **state)
{
    (void)state;
    fem_model m;
    fem_test_line(&m, 2, 2.0, 1e9, 1e-4, 7850, 1e6, FEM_CABLE, 1);
    m.f_point[3 * 1 + 2] = -1e6;
    m.settings.type = FEM_STATIC;
    m.settings.max_iterations = 1;
    nc_error err;
    assert_int_equal(fem_model_finalize(&m, &err), 0);
    fem_analysis s;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    assert_int_equal(fem_analysis_static(&s, 1.0, &err), -1);
    print_message("expected error: %s\n", err.message);
    assert_int_equal(err.code, FEM_ERR_NEWTON);
    const char *at = strstr(err.message, "largest residual ");
    assert_non_null(at);
    double largest = strtod(at + strlen("largest residual "), NULL);
    assert_near_rel(largest, fabs(s.r[3 * 1 + 2]), 1e-2);
    assert_non_null(strstr(err.message, "N at node 1 (dof z)"));
    fem_analysis_free(&s);
    fem_model_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_three_element_cable),
        cmocka_unit_test(test_rounding_floor),
        cmocka_unit_test(test_compressed_truss_lu),
        cmocka_unit_test(test_flat_net_singular),
        cmocka_unit_test(test_newton_failure_names_dof),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
