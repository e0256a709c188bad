/* The interface's momentum balance (cpl_impulse.h) against hand-computed sums: the impulse the
 * particles gave, what the structure's linearised force missed of it, the share and the
 * guard's verdict, its floor, the scale summed step by step (impulses in opposite
 * directions do not cancel in it), and the share a step would bring before it is taken. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>

#include "../../coupler/cpl_impulse.h"

static cpl_impulse fresh(double tol_rel)
{
    cpl_impulse_settings s;
    cpl_impulse_settings_default(&s);
    s.tol_rel = tol_rel;
    cpl_impulse m;
    cpl_impulse_init(&m, &s);
    return m;
}

/* two nodes: 300 N and 100 N along −z for 1e-3 s, the structure solving with half of it */
static void test_half_missed_fires(void **state)
{
    (void)state;
    cpl_impulse m = fresh(0.05);
    const double f[6] = {0, 0, -300, 0, 0, -100}, half[6] = {0, 0, -150, 0, 0, -50};
    for (long k = 0; k < 10; k++) cpl_impulse_step(&m, k, (k + 1) * 1e-3, 1e-3, f, half, 2);
    assert_near(m.given_ns[2], -4.0, 1e-12);      /* 400 N x 10 ms */
    assert_near(m.given_abs_ns, 4.0, 1e-12);
    assert_near(m.missed_ns[2], -2.0, 1e-12);
    assert_near(cpl_impulse_missed_share(&m), 0.5, 1e-12);
    assert_true(cpl_impulse_fired(&m));
    assert_int_equal(m.first_step, 0);
    assert_near(m.first_time_s, 1e-3, 1e-15);
}

/* no correction (the plain exchange, or a converged step): nothing missed */
static void test_nothing_missed(void **state)
{
    (void)state;
    cpl_impulse m = fresh(0.05);
    const double f[3] = {10, 0, -20};
    for (long k = 0; k < 5; k++) cpl_impulse_step(&m, k, (k + 1) * 0.01, 0.01, f, NULL, 1);
    assert_near(cpl_impulse_missed_share(&m), 0.0, 0.0);
    assert_false(cpl_impulse_fired(&m));
    assert_int_equal(m.first_step, -1);
}

/* a push one way then the other: the vector sum cancels, the scale does not; 3 % missed,
 * under a 5 % limit; the share first above the limit early on does not decide the verdict,
 * the end of the run does */
static void test_scale_summed_step_by_step(void **state)
{
    (void)state;
    cpl_impulse m = fresh(0.05);
    const double down[3] = {0, 0, -100}, up[3] = {0, 0, 100};
    const double big[3] = {0, 0, -10}, none[3] = {0, 0, 0};
    cpl_impulse_step(&m, 0, 1.0, 1.0, down, big, 1);    /* 10 % missed so far */
    assert_true(cpl_impulse_fired(&m));
    assert_int_equal(m.first_step, 0);
    for (long k = 1; k < 4; k++) cpl_impulse_step(&m, k, k + 1.0, 1.0, k % 2 ? up : down, none, 1);
    assert_near(m.given_ns[2], 0.0, 1e-12);
    assert_near(m.given_abs_ns, 400.0, 1e-12);
    assert_near(cpl_impulse_missed_share(&m), 10.0 / 400.0, 1e-12);
    assert_false(cpl_impulse_fired(&m));
    assert_int_equal(m.first_step, 0);   /* kept: from when */
}

/* below tol_abs_ns of interface impulse there is no verdict */
static void test_floor(void **state)
{
    (void)state;
    cpl_impulse m = fresh(0.05);
    const double f[3] = {0, 0, -1e-9}, c[3] = {0, 0, -1e-9};
    cpl_impulse_step(&m, 0, 1e-3, 1e-3, f, c, 1);
    assert_near(cpl_impulse_missed_share(&m), 1.0, 1e-12);
    assert_false(cpl_impulse_fired(&m));
}

/* the share a step would bring (cpl_loop's convergence test) is the share after taking it:
 * 100 N s given with 10 N s missed, then a step of 5 N along +z for 2 s missing 1 N along −z:
 * |−10 − 2| / (100 + 10) by hand, and the same as cpl_impulse_step then gives, the step's
 * own share 1/5; before any impulse, 0 */
static void test_share_after_a_step(void **state)
{
    (void)state;
    cpl_impulse m = fresh(0.05);
    const double f[3] = {0, 0, 5}, c[3] = {0, 0, -1}, zero[3] = {0, 0, 0};
    double own = -1.0;
    assert_near(cpl_impulse_share_after(&m, 1.0, zero, zero, 1, &own), 0.0, 0.0);
    assert_near(own, 0.0, 0.0);
    cpl_impulse_share_after(&m, 1.0, zero, c, 1, &own);
    assert_true(isinf(own));   /* a correction without force */
    const double down[3] = {0, 0, -100}, big[3] = {0, 0, -10};
    cpl_impulse_step(&m, 0, 1.0, 1.0, down, big, 1);
    const double after = cpl_impulse_share_after(&m, 2.0, f, c, 1, &own);
    assert_near(after, 12.0 / 110.0, 1e-15);
    assert_near(own, 1.0 / 5.0, 1e-15);   /* the step alone: 1 N of 5 N */
    assert_near(cpl_impulse_missed_share(&m), 0.1, 1e-15);   /* unchanged by asking */
    cpl_impulse_step(&m, 1, 3.0, 2.0, f, c, 1);
    assert_near(cpl_impulse_missed_share(&m), after, 1e-15);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_half_missed_fires),
        cmocka_unit_test(test_nothing_missed),
        cmocka_unit_test(test_scale_summed_step_by_step),
        cmocka_unit_test(test_floor),
        cmocka_unit_test(test_share_after_a_step),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
