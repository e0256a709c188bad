/* nc_test_assert — cmocka assertions on doubles that print the values they compare.
 *
 * cmocka 1.1.5 (Debian 12) has no double-precision comparison, and assert_true(fabs(a - b) <
 * tol) says only "fabs(a - b) < tol" when it fails. These macros print both values, their
 * difference and the tolerance, then fail the test at the caller's line.
 *
 *   assert_near(actual, expected, tol)      |actual - expected| <= tol (absolute)
 *   assert_near_rel(actual, expected, rel)  |actual - expected| <= rel * |expected|
 *   assert_below(value, limit)              value < limit
 * A NaN never passes.
 */
#ifndef NC_TEST_ASSERT_H
#define NC_TEST_ASSERT_H

#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

static inline void nc_test_near(double actual, double expected, double tol, const char *a_text,
                                const char *e_text, const char *file, int line)
{
    double diff = fabs(actual - expected);
    if (diff <= tol) return;   /* false for NaN */
    print_error("%s = %.17g, expected %s = %.17g: difference %.3e > tolerance %.3e\n", a_text,
                actual, e_text, expected, diff, tol);
    _fail(file, line);
}

static inline void nc_test_below(double value, double limit, const char *v_text,
                                 const char *l_text, const char *file, int line)
{
    if (value < limit) return;
    print_error("%s = %.17g is not below %s = %.17g\n", v_text, value, l_text, limit);
    _fail(file, line);
}

#define assert_near(actual, expected, tol) \
    nc_test_near((actual), (expected), (tol), #actual, #expected, __FILE__, __LINE__)
#define assert_near_rel(actual, expected, rel) \
    nc_test_near((actual), (expected), (rel) * fabs((double)(expected)), #actual, #expected, \
                 __FILE__, __LINE__)
#define assert_below(value, limit) \
    nc_test_below((value), (limit), #value, #limit, __FILE__, __LINE__)

#endif
