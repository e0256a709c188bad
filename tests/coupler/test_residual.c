/* Unit tests of cpl_residual (eqs. (27)–(30)) and cpl_interface reductions. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <string.h>

#include "../../coupler/cpl_interface.h"
#include "../../coupler/cpl_residual.h"

static void test_scaled_norm_hand_values(void **state)
{
    (void)state;
    const double x[4] = {3.0, 4.0, 0.0, 0.0};   /* ‖x‖ = 5, n = 4 -> 2.5 */
    assert_near(cpl_scaled_norm(x, 4), 2.5, 1e-15);
    assert_near(cpl_scaled_norm(x, 0), 0.0, 0.0);
    /* no overflow for huge values: ‖[1e300, 1e300]‖/sqrt(2) = 1e300 */
    const double big[2] = {1e300, -1e300};
    assert_near(cpl_scaled_norm(big, 2) / 1e300, 1.0, 1e-14);
}

static void test_residual_is_produced_minus_used(void **state)
{
    (void)state;
    const double produced[3] = {1.0, 2.0, 3.0}, used[3] = {1.0, 0.0, 5.0};
    double r[3];
    double norm = cpl_residual(produced, used, r, 3);
    assert_near(r[0], 0.0, 0.0);
    assert_near(r[1], 2.0, 0.0);
    assert_near(r[2], -2.0, 0.0);
    assert_near(norm, sqrt(8.0 / 3.0), 1e-15);
}

static void test_convergence_absolute_and_relative(void **state)
{
    (void)state;
    assert_true(cpl_converged(0.9e-6, 1.0, 1e-6, 0.0));
    assert_false(cpl_converged(1.1e-6, 1.0, 1e-6, 0.0));
    /* relative: 1e-3 of a value of norm 10 -> 1e-2 */
    assert_true(cpl_converged(0.5e-2, 10.0, 1e-6, 1e-3));
    assert_false(cpl_converged(2e-2, 10.0, 1e-6, 1e-3));
    assert_false(cpl_converged(NAN, 1.0, 1e-6, 1e-3));
}

static void test_total_force_and_mesh_checks(void **state)
{
    (void)state;
    const double f[6] = {1, 2, 3, -1, 0, 4};
    double t[3];
    cpl_total_force(f, 2, t);
    assert_near(t[0], 0.0, 0.0);
    assert_near(t[1], 2.0, 0.0);
    assert_near(t[2], 7.0, 0.0);
    assert_near(cpl_max_abs(f, 6), 4.0, 0.0);

    cpl_mesh mesh;
    nc_error err;
    const int32_t ids[2] = {5, 7};
    const double xyz[6] = {0, 0, 0, 1, 0, 0};
    const int32_t good[2] = {0, 1}, bad[2] = {0, 2};
    assert_int_equal(cpl_mesh_init(&mesh, 2, ids, xyz, 1, good, "fem", &err), 0);
    cpl_mesh_free(&mesh);
    assert_int_equal(cpl_mesh_init(&mesh, 2, ids, xyz, 1, bad, "fem", &err), -1);
    assert_non_null(strstr(err.message, "elements[0][1] = 2"));
}

/* Node lists from a participant or a checkpoint index the coupler's arrays: out of range, or
 * twice where each node is listed once (compliance_nodes), is an error naming the array, the
 * row and the node; a linearisation's pairs (two to a row) may repeat a node. */
static void test_node_list_check(void **state)
{
    (void)state;
    nc_error err;
    const int32_t good[3] = {4, 0, 2}, negative[2] = {1, -1}, beyond[2] = {0, 5},
                  twice[3] = {3, 1, 3}, pairs[4] = {2, 2, 2, 6};
    assert_int_equal(cpl_node_list_check(good, 3, 1, 5, 1, "compliance_nodes", &err), 0);
    assert_int_equal(cpl_node_list_check(negative, 2, 1, 5, 1, "compliance_nodes", &err), -1);
    assert_string_equal(err.message, "compliance_nodes row 1: node -1 is not an interface node (0..4)");
    assert_int_equal(cpl_node_list_check(beyond, 2, 1, 5, 1, "compliance_nodes", &err), -1);
    assert_string_equal(err.message, "compliance_nodes row 1: node 5 is not an interface node (0..4)");
    assert_int_equal(cpl_node_list_check(twice, 3, 1, 5, 1, "compliance_nodes", &err), -1);
    assert_string_equal(err.message, "compliance_nodes row 2: node 3 is listed twice");
    assert_int_equal(cpl_node_list_check(pairs, 2, 2, 5, 0, "jacobian_nodes", &err), 0);
    assert_int_equal(cpl_node_list_check(pairs, 4, 2, 5, 0, "jacobian_nodes", &err), -1);
    assert_string_equal(err.message, "jacobian_nodes row 1: node 6 is not an interface node (0..4)");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scaled_norm_hand_values),
        cmocka_unit_test(test_residual_is_produced_minus_used),
        cmocka_unit_test(test_convergence_absolute_and_relative),
        cmocka_unit_test(test_total_force_and_mesh_checks),
        cmocka_unit_test(test_node_list_check),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
