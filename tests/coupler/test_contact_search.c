/* Unit tests of cpl_contact_search: the point along an interface step that lost its contact
 * at which contact backtracking solves the DEM again.
 *
 * The force along the step is a model law φ(t) = c (t₀ − t)^p (zero from t₀ on) with its exact
 * slope, driven by the same loop as the coupler's (evaluate where the search proposes, at most
 * a budget of solves, end at its best point). The target is what the linearisation about t = 0
 * predicts at t = 1, φ(0) + φ'(0), as in the coupler. Checked against the law itself: with
 * p = 1/4 (a damped contact's end) and the contact ending just past p, the target is 0.6 % of
 * φ(0) (cable_impact's separations: 216 N of 28.8 kN) and the search ends within its band
 * [φ_T/4, 5/4 φ_T]; the halving it replaces ends at 59 % of φ(0). Without a target the first
 * point with contact is taken; a law the fit does not describe (a jump) still ends at a point
 * with contact. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>

#include "../../coupler/cpl_contact_search.h"

typedef struct law {
    double c, t0, p;
    double jump;        /* > 0: φ = jump + c (t₀ − t) before t₀ instead */
    double spring;      /* + spring (t₀ − t)^1.5: a Hertz spring beside the dashpot */
} law;

static double law_force(const law *w, double t)
{
    if (t >= w->t0) return 0.0;
    if (w->jump > 0.0) return w->jump + w->c * (w->t0 - t);
    return w->c * pow(w->t0 - t, w->p) + w->spring * pow(w->t0 - t, 1.5);
}

static double law_slope(const law *w, double t)
{
    if (t >= w->t0) return NAN;
    if (w->jump > 0.0) return -w->c;
    return -w->c * w->p * pow(w->t0 - t, w->p - 1.0) - 1.5 * w->spring * sqrt(w->t0 - t);
}

/* The coupler's loop (cpl_loop.c backtrack): returns the point ended at (-1: none with
 * contact), the number of evaluations in *evaluations. */
static double run_search(const law *w, double target, int budget, int *evaluations)
{
    cpl_contact_search s;
    cpl_contact_search_begin(&s, law_force(w, 0.0), law_slope(w, 0.0), target);
    int n = 0;
    while (n < budget && !s.done) {
        const double t = cpl_contact_search_next(&s);
        assert_true(t > s.t_contact && t < s.t_past);
        const double phi = law_force(w, t);
        cpl_contact_search_add(&s, t, phi > 0.0, phi, phi > 0.0 ? law_slope(w, t) : NAN);
        n++;
    }
    *evaluations = n;
    return s.t_best;
}

static void test_damped_contact_end(void **state)
{
    (void)state;
    /* φ(0) = 28.8 kN, the contact ends at t₀ = 0.2515, p = 1/4: φ(0) + φ'(0) = 0.6 % of φ(0) */
    law w = {0.0, 0.2515, 0.25, 0.0, 0.0};
    w.c = 28.8e3 / pow(w.t0, w.p);
    const double phi0 = law_force(&w, 0.0), target = phi0 + law_slope(&w, 0.0);
    assert_near_rel(target / phi0, 1.0 - w.p / w.t0, 1e-12);
    assert_below(target / phi0, 0.01);
    int n;
    const double t = run_search(&w, target, 8, &n);
    assert_true(t >= 0.0);
    const double phi = law_force(&w, t);
    print_message("ends at t = %.12g after %d solves: φ = %.4g, target %.4g\n", t, n, phi, target);
    assert_true(phi >= CPL_CONTACT_SEARCH_BELOW * target);
    assert_true(phi <= CPL_CONTACT_SEARCH_ABOVE * target);
    /* what halving until contact ends at: 0.25 of the way, 28 % of the force left */
    assert_below(0.25, law_force(&w, 0.25) / phi0);
}

/* A dashpot and a spring whose sum is no power law: the fit's exponent changes from point to
 * point (0.54 at t = 0, 1/4 at the end), and its first fits go past the contact's end. */
static void test_spring_and_dashpot(void **state)
{
    (void)state;
    law w = {1e3, 0.545, 0.25, 0.0, 0.0};   /* target 1.3 % of φ(0) */
    w.spring = 0.3 * w.c * pow(w.t0, w.p) / pow(w.t0, 1.5);
    const double target = law_force(&w, 0.0) + law_slope(&w, 0.0);
    assert_true(target > 0.0);
    int n;
    const double t = run_search(&w, target, 8, &n);
    const double phi = law_force(&w, t);
    print_message("ends at t = %.12g after %d solves: φ = %.4g, target %.4g, φ(0) %.4g\n", t,
                  n, phi, target, law_force(&w, 0.0));
    /* the band is not reached within the budget here (3.7 φ_T after 8 solves, the band after
     * 9), but the point is 9 times nearer than halving's (the first point with contact, t =
     * 0.5: 35 φ_T) */
    assert_true(phi > 0.0 && phi <= 5.0 * target);
    assert_below(30.0 * target, law_force(&w, 0.5));
    assert_true(run_search(&w, target, 12, &n) >= 0.0 && n <= 10);
}

/* The same law with a contact ending well before the Newton point (target 12 % of φ(0)). */
static void test_earlier_end(void **state)
{
    (void)state;
    law w = {1e4, 0.2837, 0.25, 0.0, 0.0};
    const double target = law_force(&w, 0.0) + law_slope(&w, 0.0);
    int n;
    const double t = run_search(&w, target, 8, &n);
    const double phi = law_force(&w, t);
    assert_true(phi >= CPL_CONTACT_SEARCH_BELOW * target && phi <= CPL_CONTACT_SEARCH_ABOVE * target);
}

/* No target: the first point with contact, halving from the step's end, as before. */
static void test_no_target_first_contact(void **state)
{
    (void)state;
    law w = {1e4, 0.3, 1.5, 0.0, 0.0};
    int n;
    const double t = run_search(&w, 0.0, 8, &n);
    assert_near(t, 0.25, 0.0);   /* 0.5 has no contact, 0.25 has */
    assert_int_equal(n, 2);
}

/* A force that jumps to zero at its end (no power law fits it): within the budget the search
 * ends at a point with contact, never at one without. */
static void test_jump_ends_with_contact(void **state)
{
    (void)state;
    law w = {1e3, 0.4, 1.0, 5e3, 0.0};
    const double target = 1e2;   /* below the jump: the band cannot be reached */
    int n;
    const double t = run_search(&w, target, 8, &n);
    assert_int_equal(n, 8);
    assert_true(t > 0.0 && t < w.t0);
    assert_true(law_force(&w, t) > 0.0);
    /* ... and it is the point nearest the end among those tried: within 1 % of the step */
    assert_below(w.t0 - t, 0.01);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_damped_contact_end),
        cmocka_unit_test(test_spring_and_dashpot),
        cmocka_unit_test(test_earlier_end),
        cmocka_unit_test(test_no_target_first_contact),
        cmocka_unit_test(test_jump_ends_with_contact),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
