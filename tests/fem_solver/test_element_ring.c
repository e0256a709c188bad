/* test_element_ring — the ring-net connection (type "ring", fem_element_ring.h) reproduces
 * its two-phase law through the solver: a ring of a ROCCO-type net (bending stiffness
 * 5e4 N/m until it is stretched taut after 0.15 m, then a membrane stiffness of 5e6 N/m)
 * between an anchor and a node (free along the ring) loaded along it, read from fem.json; the static
 * elongation under each load against the inverted law, the strain energy against the
 * integral of the law, the tangent against finite differences, and no compression. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "../../fem_solver/fem_analysis.h"
#include "../../fem_solver/fem_element_ring.h"
#include "../../fem_solver/fem_input.h"
#include "fem_test_util.h"

#define KB 5e4
#define KM 5e6
#define DM 0.15

static const char *ring_json(double load_n)
{
    static char text[1024];
    snprintf(text, sizeof text,
             "{\"nodes\": [[0, 0, 0], [0.3, 0, 0]], \"elements\": [[0, 1]],\n"
             " \"element_sets\": [{\"name\": \"rings\", \"type\": \"ring\", \"bending_stiffness_n_per_m\": %g,\n"
             "   \"membrane_stiffness_n_per_m\": %g, \"membrane_elongation_m\": %g}],\n"
             " \"supports\": [{\"nodes\": [0], \"dofs\": \"xyz\"}, {\"nodes\": [1], \"dofs\": \"yz\"}],\n"
             " \"point_loads\": [{\"nodes\": [1], \"force_n\": [%.17g, 0, 0]}],\n"
             " \"gravity_m_s2\": [0, 0, 0], \"analysis\": {\"type\": \"static\", \"load_steps\": 10}}\n",
             KB, KM, DM, load_n);
    return text;
}

/* the inverse of the law */
static double elongation(double F)
{
    return F <= KB * DM ? F / KB : DM + (F - KB * DM) / KM;
}

static void test_law_through_solver(void **state)
{
    (void)state;
    const double loads[4] = {3e3, 7.4e3, 2e4, 5e4};   /* bending, just below the kink, membrane */
    for (int i = 0; i < 4; i++) {
        fem_model m;
        nc_error err;
        if (fem_input_load(fem_test_write("ring.json", ring_json(loads[i])), &m, &err)) fail_msg("%s", err.message);
        fem_analysis s;
        assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
        for (int k = 1; k <= 10; k++)
            if (fem_analysis_static(&s, 0.1 * k, &err)) fail_msg("load %g N: %s", loads[i], err.message);
        double l = 0;
        for (int c = 0; c < 3; c++) {
            double d = m.X[3 + c] + s.cur.u[3 + c];
            l += d * d;
        }
        double delta = sqrt(l) - m.L0[0];
        print_message("load %.0f N: elongation %.6f m (law %.6f), force %.3f N\n", loads[i], delta,
                      elongation(loads[i]), s.axial[0]);
        assert_near_rel(s.axial[0], loads[i], 1e-9);
        assert_near_rel(delta, elongation(loads[i]), 1e-9);
        /* strain energy = the integral of the law (closed form of the two linear phases) */
        double W;
        fem_analysis_energy(&s, NULL, &W);
        double d1 = fmin(delta, DM), d2 = fmax(delta - DM, 0.0);
        assert_near_rel(W, 0.5 * KB * d1 * d1 + KB * DM * d2 + 0.5 * KM * d2 * d2, 1e-9);
        fem_analysis_free(&s);
        fem_model_free(&m);
    }
}

static void test_tangent_and_compression(void **state)
{
    (void)state;
    fem_model m;
    nc_error err;
    if (fem_input_load(fem_test_write("ring2.json", ring_json(1e3)), &m, &err)) fail_msg("%s", err.message);
    const fem_element_ops *ops = fem_element_type(m.set_types[0].type);
    assert_string_equal(ops->name, "ring");
    const double stretch[2] = {0.05, 0.3};   /* bending, membrane */
    for (int t = 0; t < 2; t++) {
        double u[6] = {0, 0, 0, 0, 0, 0};
        for (int c = 0; c < 3; c++) u[3 + c] = stretch[t] * m.X[3 + c] / m.L0[0] + 0.01 * (c - 1);
        fem_element_ctx ctx = {&m, &m.sets[0], m.set_types[0].param, 0, 0, 1, u, NULL, 0};
        double f[3], Kb[9], fp[3], fm[3], K2[9];
        int slack;
        ops->pair_response(&ctx, f, Kb, &slack);
        for (int j = 0; j < 3; j++) {
            double h = 1e-8;
            u[3 + j] += h;
            ops->pair_response(&ctx, fp, K2, &slack);
            u[3 + j] -= 2 * h;
            ops->pair_response(&ctx, fm, K2, &slack);
            u[3 + j] += h;
            double kmax = fmax(fabs(Kb[0]), fmax(fabs(Kb[4]), fabs(Kb[8])));
            for (int i = 0; i < 3; i++) assert_near(Kb[3 * i + j], (fp[i] - fm[i]) / (2 * h), 1e-6 * kmax);
        }
    }
    double kt;
    assert_near(fem_ring_force(m.set_types[0].param, -0.01, &kt), 0.0, 0.0);
    assert_near(kt, 0.0, 0.0);
    fem_model_free(&m);
    /* a membrane softer than the bending phase is an input error */
    const char *bad =
        "{\"nodes\": [[0, 0, 0], [1, 0, 0]], \"elements\": [[0, 1]], \"element_sets\": [{\"type\": \"ring\","
        " \"bending_stiffness_n_per_m\": 5e6, \"membrane_stiffness_n_per_m\": 5e4, \"membrane_elongation_m\": 0.1}],"
        " \"supports\": [{\"nodes\": [0, 1], \"dofs\": \"xyz\"}], \"analysis\": {\"type\": \"static\"}}";
    assert_int_not_equal(fem_input_load(fem_test_write("ring3.json", bad), &m, &err), 0);
    assert_non_null(strstr(err.message, "element_sets[0].membrane_stiffness_n_per_m"));
    fem_model_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_law_through_solver),
        cmocka_unit_test(test_tangent_and_compression),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
