/* Unit tests of the relaxation methods on fixed-point problems x = H(x) with known answers:
 * constant (31)–(33), Aitken (34) with first-iteration cap, clipping and zero-denominator
 * guard, its safeguard and Newton's regime, IQN-ILS (exact for an affine map after at most
 * n + 1 updates), QR filter, reuse. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../../coupler/cpl_relax.h"

static void set(cpl_relax_settings *s, const char *key, double value)
{
    nc_error err;
    if (cpl_relax_settings_set(s, key, value, &err)) fail_msg("%s", err.message);
}

static cpl_relax *create(const cpl_relax_settings *s, size_t n, size_t blocks)
{
    cpl_relax *r = NULL;
    nc_error err;
    assert_int_equal(cpl_relax_settings_check(s, "relaxation", &err), 0);
    assert_int_equal(cpl_relax_create(&r, s, n, blocks, &err), 0);
    return r;
}

static cpl_relax *make(const char *method, double alpha, size_t n, size_t blocks)
{
    cpl_relax_settings s;
    nc_error err;
    cpl_relax_settings_default(&s);
    assert_int_equal(cpl_relax_settings_select(&s, method, &err), 0);
    s.alpha = alpha;
    set(&s, "reuse_steps", 0);
    set(&s, "filter", 1e-10);   /* exactness claims need all independent columns */
    return create(&s, n, blocks);
}

/* Aitken's settings with α0, first-iteration cap, clipping range and safeguard. */
static cpl_relax_settings aitken_settings(double alpha0, double first_cap, double alpha_min,
                                          double alpha_max, double restart_growth)
{
    cpl_relax_settings s;
    nc_error err;
    cpl_relax_settings_default(&s);
    assert_int_equal(cpl_relax_settings_select(&s, "aitken", &err), 0);
    s.alpha = alpha0;
    set(&s, "first_iteration_cap", first_cap);
    set(&s, "alpha_min", alpha_min);
    set(&s, "alpha_max", alpha_max);
    set(&s, "restart_growth", restart_growth);
    return s;
}

static cpl_relax *make_aitken(double alpha0, double first_cap, double alpha_min,
                              double alpha_max, double restart_growth, size_t n, size_t blocks)
{
    const cpl_relax_settings s = aitken_settings(alpha0, first_cap, alpha_min, alpha_max,
                                                 restart_growth);
    return create(&s, n, blocks);
}

/* One update; returns the α applied. */
static double update(cpl_relax *r, const double *x_in, const double *x_out, double *x_next)
{
    double alpha;
    nc_error err;
    if (cpl_relax_update(r, x_in, x_out, x_next, &alpha, &err)) fail_msg("%s", err.message);
    return alpha;
}

static double counter(const cpl_relax *r, const char *name)
{
    double value;
    assert_int_equal(cpl_relax_counter(r, name, &value), 0);
    return value;
}

static void test_constant_and_none(void **state)
{
    (void)state;
    cpl_relax *r = make("constant", 0.25, 2, 1);
    const double in[2] = {1.0, 2.0}, out[2] = {5.0, -2.0};
    double next[2], alpha;
    nc_error err;
    cpl_relax_begin_step(r);
    assert_int_equal(cpl_relax_update(r, in, out, next, &alpha, &err), 0);
    assert_near(next[0], 2.0, 1e-15);   /* 1 + 0.25 · 4 */
    assert_near(next[1], 1.0, 1e-15);   /* 2 + 0.25 · (−4) */
    assert_near(alpha, 0.25, 0.0);
    cpl_relax_free(r);
    r = make("none", 0.5, 2, 1);
    assert_int_equal(cpl_relax_update(r, in, out, next, &alpha, &err), 0);
    assert_near(next[0], 5.0, 0.0);
    assert_near(alpha, 1.0, 0.0);
    cpl_relax_free(r);
}

/* Scalar affine map H(x) = a x + b: Aitken's second factor is 1/(1 − a) exactly, so the
 * second update lands on the fixed point x* = b / (1 − a) (to round-off, 1e-12). */
static void test_aitken_exact_on_scalar_affine_map(void **state)
{
    (void)state;
    const double a = -3.0, b = 2.0, xstar = b / (1.0 - a);
    cpl_relax *r = make("aitken", 0.5, 1, 1);
    double x = 0.0, out, alpha;
    nc_error err;
    cpl_relax_begin_step(r);
    for (int k = 0; k < 2; k++) {
        out = a * x + b;
        assert_int_equal(cpl_relax_update(r, &x, &out, &x, &alpha, &err), 0);
    }
    assert_near(alpha, 1.0 / (1.0 - a), 1e-12);
    assert_near(x, xstar, 1e-12);
    cpl_relax_free(r);
}

/* Settings from a `relaxation` object as coupler.json gives it. */
static cpl_relax_settings parsed(const char *json)
{
    cpl_relax_settings s;
    nc_error err;
    cpl_relax_settings_default(&s);
    cJSON *obj = cJSON_Parse(json);
    assert_non_null(obj);
    assert_int_equal(cpl_relax_settings_parse(&s, obj, "test", &err), 0);
    cJSON_Delete(obj);
    return s;
}

/* The α of the first update of a step (input 0, output 1) by a relaxation made from s with
 * the linearisation on or off, and *x_next after it; with second != NULL also the α of the
 * next step's first update. */
static double first_alpha(const cpl_relax_settings *s, int linearised, double *x_next,
                          double *second)
{
    cpl_relax *r = create(s, 1, 1);
    cpl_relax_set_linearised(r, linearised);
    double x = 0.0, out = 1.0;
    cpl_relax_begin_step(r);
    const double first = update(r, &x, &out, &x);
    if (x_next) *x_next = x;
    if (second) {
        x = 0.0;
        cpl_relax_begin_step(r);
        *second = update(r, &x, &out, &x);
    }
    cpl_relax_free(r);
    return first;
}

/* first_iteration_cap not given: 1 in a step's first iteration while Newton's rule acts
 * (the FEM solves with the linearisation: its answer is Newton's full step from the
 * predictor), 0.5 in the plain exchange; a given cap acts in both */
static void test_aitken_first_iteration_cap_by_regime(void **state)
{
    (void)state;
    for (int given = 0; given < 2; given++)
        for (int linearised = 0; linearised < 2; linearised++) {
            const cpl_relax_settings s =
                parsed(given ? "{\"method\": \"aitken\", \"alpha\": 0.9, \"first_iteration_cap\": 0.7}"
                             : "{\"method\": \"aitken\", \"alpha\": 0.9}");
            double second;
            const double first = first_alpha(&s, linearised, NULL, &second);
            const double cap = given ? 0.7 : linearised ? 1.0 : 0.5;
            /* the run's very first iteration: α0 in the plain exchange, min(1, cap) with the
             * rule; a later step's first: min(cap, |α_prev|), or min(1, cap) */
            assert_near(first, linearised ? cap : 0.9, 0.0);
            assert_near(second, linearised ? cap : fmin(cap, 0.9), 0.0);
        }
}

static void test_aitken_first_iteration_cap_and_sign(void **state)
{
    (void)state;
    /* α0 = 0.9, cap 0.5: a later step's first α is min(0.5, 0.9) */
    cpl_relax *r = make_aitken(0.9, 0.5, -1.0, 2.0, 0.0, 1, 1);
    double x = 0.0, out = 1.0;
    cpl_relax_begin_step(r);
    assert_near(update(r, &x, &out, &x), 0.9, 0.0);   /* very first: α0 */
    x = 0.0;
    cpl_relax_begin_step(r);
    assert_near(update(r, &x, &out, &x), 0.5, 0.0);   /* capped */
    /* a negative previous α keeps its sign: sign(α)·min(cap, |α|). From x = 0.5 (r = 1),
     * out = 3.5 (r = 3) gives α = −0.5 · 1 · 2 / 4 = −0.25 by eq. (34) */
    out = 3.5;
    assert_near(update(r, &x, &out, &x), -0.25, 0.0);
    x = 0.0;
    out = 1.0;
    cpl_relax_begin_step(r);
    assert_near(update(r, &x, &out, &x), -0.25, 0.0);
    cpl_relax_free(r);
}

static void test_aitken_clipping_and_zero_denominator(void **state)
{
    (void)state;
    /* H(x) = 3x + 1 (slope > 1): eq. (34) gives α = 1/(1 − 3) = −0.5, clipped to 1e-3 */
    cpl_relax *r = make_aitken(0.5, 0.5, 1e-3, 2.0, 0.0, 1, 1);
    double x = 0.0, out, alpha = 0.0;
    cpl_relax_begin_step(r);
    for (int k = 0; k < 2; k++) {
        out = 3.0 * x + 1.0;
        alpha = update(r, &x, &out, &x);
    }
    assert_near(alpha, 1e-3, 0.0);
    cpl_relax_free(r);

    /* identical residuals twice: ‖Δr‖ = 0, α must stay the previous one (no NaN) */
    r = make_aitken(0.4, 0.5, 1e-6, 2.0, 0.0, 2, 2);
    double in[2] = {1.0, 1.0}, o[2] = {2.0, 3.0}, next[2];
    cpl_relax_begin_step(r);
    update(r, in, o, next);
    alpha = update(r, in, o, next);
    assert_near(alpha, 0.4, 0.0);
    assert_true(isfinite(next[0]) && isfinite(next[1]));
    /* blocks get separate factors: block 1's residual is twice block 0's, same α here */
    assert_near(next[1], 1.0 + 0.4 * 2.0, 0.0);
    cpl_relax_free(r);
}

/* On/off contact as a scalar map (the first contact step of case 7.2 with a damped contact):
 * the structure's end position x, a particle whose surface ends at s = -0.01 below the free
 * position 0; no contact (x <= s): the structure ends free, H = 0; contact: H = -g (x - s),
 * g = 40 (contact force gain of the stiff contact on a light node). Fixed point
 * x* = g s / (1 + g), in contact just above s. Plain Aitken from x = 0 (the predictor, deep
 * contact) cycles with period 3: two contact-free iterates make H locally constant, eq. (34)
 * gives alpha = 1, i.e. H = 0 = the predictor again (only the slow decay of alpha lets it out
 * after about 60 evaluations). restart_growth = 2 goes back to the best iterate with half
 * its alpha instead and converges in 24 evaluations (tolerance 1e-9 on |x - x*|). */
static double onoff_map(double x)
{
    const double s = -0.01, g = 40.0;
    return x > s ? -g * (x - s) : 0.0;
}

static int onoff_evaluations(double restart_growth, int max_eval, double *x_end, long *restarts)
{
    cpl_relax *r = make_aitken(0.5, 0.5, 1e-6, 2.0, restart_growth, 1, 1);
    const double xstar = 40.0 * -0.01 / 41.0;
    double x = 0.0;
    int k;
    cpl_relax_begin_step(r);
    for (k = 1; k <= max_eval; k++) {
        double out = onoff_map(x);
        if (fabs(out - x) < 1e-9 && fabs(x - xstar) < 1e-9) break;
        if (k == 4 && restart_growth == 0.0) assert_near(x, 0.0, 1e-15); /* the cycle */
        update(r, &x, &out, &x);
    }
    *x_end = x;
    *restarts = (long)counter(r, "restarts");
    cpl_relax_free(r);
    return k;
}

static void test_aitken_restart_breaks_onoff_cycle(void **state)
{
    (void)state;
    double x;
    long restarts;
    int plain = onoff_evaluations(0.0, 30, &x, &restarts);
    assert_true(plain > 30);                           /* not converged in 30 evaluations */
    assert_below(1e-3, fabs(x - 40.0 * -0.01 / 41.0));
    assert_int_equal(restarts, 0);
    int safe = onoff_evaluations(2.0, 30, &x, &restarts);
    print_message("on/off contact map: plain Aitken > 30 evaluations, restart_growth 2: %d "
                  "(%ld restarts)\n", safe, restarts);
    assert_true(safe <= 30);
    assert_near(x, 40.0 * -0.01 / 41.0, 1e-9);
    assert_true(restarts > 0);
}

/* A kink in the contact law (the steel net at restitution 0.1, Δt 1.6e-5 s): on one side the
 * structure's answer does not depend on the input (x < 0.8: always 1), on the other it does.
 * The iterates 0 → 1 → 0.556 → 0.714 see the answer 1 twice in a row, so eq. (34) gives
 * α = 1 and sends the iteration to 1 again, an input already tried whose answer is known: a
 * cycle of period 3 in which the residual never grows 4-fold (1, 0.8, 0.44, 0.29), so the
 * growth test does not see it. The repeat test restarts from the best iterate (0.714, the
 * last) with half its α instead; off (restart_growth 0, the paper's Aitken) the cycle
 * stays. */
static void test_aitken_restart_on_repeated_input(void **state)
{
    (void)state;
    const double in[4] = {0.0, 1.0, 5.0 / 9.0, 5.0 / 7.0}, out[4] = {1.0, 0.2, 1.0, 1.0};
    for (int on = 0; on < 2; on++) {
        cpl_relax *r = make_aitken(1.0, 1.0, 1e-6, 2.0, on ? 4.0 : 0.0, 1, 1);
        double next = 0.0;
        cpl_relax_begin_step(r);
        for (int k = 0; k < 4; k++) {
            if (k > 0) assert_near(next, in[k], 1e-12);   /* the sequence above */
            update(r, &in[k], &out[k], &next);
        }
        if (on) {
            assert_near(next, 5.0 / 7.0 + 0.5 * (1.0 - 5.0 / 7.0), 1e-12);
            assert_int_equal((long)counter(r, "restarts"), 1);
        } else {
            assert_near(next, 1.0, 1e-12);                  /* back to the second input */
            assert_int_equal((long)counter(r, "restarts"), 0);
        }
        cpl_relax_free(r);
    }
}

/* The safeguard never fires on a contracting affine map (residual decreasing), so the exact
 * secant of (34) is untouched: same result as without it. */
static void test_aitken_restart_inactive_when_converging(void **state)
{
    (void)state;
    for (int on = 0; on < 2; on++) {
        cpl_relax *r = make_aitken(0.5, 0.5, 1e-6, 2.0, on ? 2.0 : 0.0, 1, 1);
        double x = 0.0, out;
        cpl_relax_begin_step(r);
        for (int k = 0; k < 2; k++) {
            out = 0.5 * x + 1.0;   /* x* = 2 */
            update(r, &x, &out, &x);
        }
        assert_near(x, 2.0, 1e-12);
        assert_int_equal((long)counter(r, "restarts"), 0);
        cpl_relax_free(r);
    }
}

/* Aitken from the full step (α 1, first_iteration_cap 1, defaults otherwise) with
 * newton_contraction θ. */
static cpl_relax *make_aitken_newton(double theta)
{
    cpl_relax_settings s = aitken_settings(1.0, 1.0, 1e-6, 2.0, 4.0);
    set(&s, "newton_contraction", theta);
    return create(&s, 1, 1);
}

/* Newton's map of f(x) = x³ + x − 10 (root 2): H(x) = x − f(x)/f'(x), what the FEM's answer
 * is with the interface Jacobian. Aitken from the full step with contraction θ, the
 * linearisation flagged or not; the number of updates until |r| < 1e-12, the ratio
 * |r_k| / |r_{k−1}|² of the last update and the updates the rule relaxed with α = 1. */
static int newton_map_updates(double theta, int linearised, double *last_ratio, long *newton)
{
    cpl_relax *r = make_aitken_newton(theta);
    cpl_relax_set_linearised(r, linearised);
    cpl_relax_begin_step(r);
    double x = 3.0, r_prev = NAN;
    int k = 0;
    for (; k < 50; k++) {
        const double out = x - (x * x * x + x - 10.0) / (3.0 * x * x + 1.0);
        const double res = fabs(out - x);
        if (res < 1e-12) break;
        if (k > 0) *last_ratio = res / (r_prev * r_prev);
        r_prev = res;
        update(r, &x, &out, &x);
    }
    *newton = (long)counter(r, "full_steps");
    cpl_relax_free(r);
    return k;
}

/* Newton's regime: on Newton's map eq. (34) makes the convergence merely superlinear (each
 * α − 1 is of the order of the last contraction and keeps that share of the residual);
 * with the linearisation flagged and newton_contraction 0.5 every update takes α = 1 and the
 * convergence is quadratic: |r_k| ≤ |r_{k−1}|² (Newton's constant f''/2f' is 0.46 at the
 * root). Without the flag (the plain exchange) the rule does not act: the same as θ = 0. */
static void test_aitken_newton_regime(void **state)
{
    (void)state;
    double ratio_newton = NAN, ratio_secant = NAN, ratio_off = NAN;
    long newton_on, newton_zero, newton_off;
    const int on = newton_map_updates(0.5, 1, &ratio_newton, &newton_on);
    const int zero = newton_map_updates(0.0, 1, &ratio_secant, &newton_zero);
    const int off = newton_map_updates(0.5, 0, &ratio_off, &newton_off);
    print_message("Newton's map x^3 + x - 10: %d updates with the rule (last |r_k|/|r_k-1|^2 "
                  "%.3g), %d with eq. (34) (%.3g)\n", on, ratio_newton, zero, ratio_secant);
    assert_true(on < zero);
    assert_true(ratio_newton <= 1.0);
    assert_int_equal(newton_on, on);      /* the rule chose every update's α */
    assert_int_equal(newton_zero, 0);
    assert_int_equal(off, zero);
    assert_int_equal(newton_off, 0);
}

/* The rule against θ = 0.5 on the affine maps H(x) = s x + 1 − s (x* = 1): the first update
 * takes α = 1 (from x = 0 to 1 − s), whose residual is then s times the first. Where |s| > θ (0.9,
 * 0.6: a θ compared without its square, 0.71, would take 0.6 for a contraction) the rule
 * steps aside and eq. (34)'s exact α = 1/(1 − s) lands on x*; where |s| ≤ θ (0.4) α = 1. */
static void test_aitken_newton_rule_steps_aside(void **state)
{
    (void)state;
    const double slopes[] = {-0.9, -0.6, -0.4};
    for (size_t i = 0; i < sizeof slopes / sizeof *slopes; i++) {
        const double s = slopes[i];
        cpl_relax *r = make_aitken_newton(0.5);
        cpl_relax_set_linearised(r, 1);
        cpl_relax_begin_step(r);
        double x = 0.0, out = s * x + 1.0 - s;
        assert_near(update(r, &x, &out, &x), 1.0, 0.0);
        out = s * x + 1.0 - s;
        const double alpha = update(r, &x, &out, &x);
        if (fabs(s) > 0.5) {
            assert_near(alpha, 1.0 / (1.0 - s), 1e-14);
            assert_near(x, 1.0, 1e-14);
            assert_int_equal((long)counter(r, "full_steps"), 1);
        } else {
            assert_near(alpha, 1.0, 0.0);
            assert_int_equal((long)counter(r, "full_steps"), 2);
        }
        cpl_relax_free(r);
    }
}

/* Affine map H(x) = A x + b with a non-symmetric A of spectral radius > 1 (plain iteration
 * diverges). IQN-ILS is exact for affine maps once it has n independent columns: the
 * (n+1)-th update (evaluation n + 2 checks it) gives x* to round-off (1e-9 relative). */
static void test_iqn_linear_in_n_plus_1_updates(void **state)
{
    (void)state;
    enum { N = 6 };
    double A[N * N], b[N];
    unsigned seed = 12345;
    for (int i = 0; i < N * N; i++) {
        seed = seed * 1103515245u + 12345u;
        A[i] = ((double)(seed >> 8 & 0xffff) / 65535.0 - 0.5) * 2.0;
    }
    for (int i = 0; i < N; i++) {
        A[i * N + i] -= 1.5;   /* makes plain fixed-point iteration diverge */
        b[i] = 1.0 + i;
    }
    cpl_relax *r = make("iqn-ils", 0.1, N, 1);
    double x[N] = {0}, out[N], alpha;
    nc_error err;
    cpl_relax_begin_step(r);
    int evaluations = 0;
    double res = INFINITY;
    for (int k = 0; k < 20; k++) {
        for (int i = 0; i < N; i++) {
            out[i] = b[i];
            for (int j = 0; j < N; j++) out[i] += A[i * N + j] * x[j];
        }
        evaluations++;
        res = 0.0;
        for (int i = 0; i < N; i++) res += (out[i] - x[i]) * (out[i] - x[i]);
        res = sqrt(res);
        if (res < 1e-9) break;
        assert_int_equal(cpl_relax_update(r, x, out, x, &alpha, &err), 0);
        if (k == 0) assert_near(alpha, 0.1, 0.0);   /* no columns: plain step */
        else assert_true(isnan(alpha));
    }
    assert_below(res, 1e-9);
    assert_true(evaluations <= N + 2);
    cpl_relax_free(r);
}

/* IQN-ILS without columns takes a plain step: with its alpha when coupler.json gives one,
 * else 1 while the FEM solves with the linearisation (Newton's full step) and 0.5 otherwise. */
static void test_iqn_plain_step_by_regime(void **state)
{
    (void)state;
    for (int given = 0; given < 2; given++)
        for (int linearised = 0; linearised < 2; linearised++) {
            const cpl_relax_settings s = parsed(given ? "{\"method\": \"iqn-ils\", \"alpha\": 0.3}"
                                                      : "{\"method\": \"iqn-ils\"}");
            double x;
            const double expected = given ? 0.3 : linearised ? 1.0 : 0.5;
            assert_near(first_alpha(&s, linearised, &x, NULL), expected, 0.0);
            assert_near(x, expected, 1e-15);
        }
}

/* The same x evaluated twice gives a zero column: the filter must drop it, no NaN. */
static void test_iqn_filter_drops_dependent_columns(void **state)
{
    (void)state;
    cpl_relax_settings s;
    nc_error err;
    cpl_relax_settings_default(&s);
    assert_int_equal(cpl_relax_settings_select(&s, "iqn-ils", &err), 0);
    s.alpha = 0.5;
    set(&s, "filter", 1e-8);
    set(&s, "reuse_steps", 0);
    cpl_relax *r = create(&s, 3, 1);
    cpl_relax_begin_step(r);
    double x[3] = {1, 2, 3}, out[3] = {2, 2, 2}, next[3];
    update(r, x, out, next);
    update(r, x, out, next);   /* identical pair -> zero column */
    assert_true(counter(r, "dropped_columns") >= 1);
    assert_int_equal((int)counter(r, "columns"), 0);
    for (int i = 0; i < 3; i++) assert_true(isfinite(next[i]));
    /* parallel columns (new step, so only these pairs count): equal residual differences */
    cpl_relax_begin_step(r);
    double x2[3] = {0, 0, 0}, o2[3] = {1, 1, 1};
    update(r, x2, o2, next);
    double x3[3] = {1, 1, 1}, o3[3] = {3, 3, 3};
    update(r, x3, o3, next);
    double x4[3] = {2, 2, 2}, o4[3] = {5, 5, 5};
    update(r, x4, o4, next);
    assert_true(counter(r, "columns") <= 1);
    cpl_relax_free(r);
}

static int solve_affine(cpl_relax *r, const double *A, const double *b, int n)
{
    double x[8] = {0}, out[8], alpha;
    nc_error err;
    cpl_relax_begin_step(r);
    for (int k = 1; k <= 30; k++) {
        double res = 0.0;
        for (int i = 0; i < n; i++) {
            out[i] = b[i];
            for (int j = 0; j < n; j++) out[i] += A[i * n + j] * x[j];
            res += (out[i] - x[i]) * (out[i] - x[i]);
        }
        if (sqrt(res) < 1e-9) {
            cpl_relax_end_step(r, x, out);
            return k;
        }
        if (cpl_relax_update(r, x, out, x, &alpha, &err)) return 99;
    }
    return 99;
}

/* Reusing the previous step's columns: the next step of the same linear map (new b)
 * needs fewer evaluations than the first. */
static void test_iqn_reuse_previous_steps(void **state)
{
    (void)state;
    enum { N = 5 };
    double A[N * N] = {0}, b1[N], b2[N];
    for (int i = 0; i < N; i++) {
        A[i * N + i] = -2.0 - 0.3 * i;
        if (i + 1 < N) A[i * N + i + 1] = 0.5;
        b1[i] = 1.0;
        b2[i] = 1.0 + 0.1 * i;
    }
    cpl_relax_settings s;
    nc_error err;
    cpl_relax_settings_default(&s);
    assert_int_equal(cpl_relax_settings_select(&s, "iqn-ils", &err), 0);
    s.alpha = 0.2;
    set(&s, "reuse_steps", 2);
    set(&s, "filter", 1e-10);
    cpl_relax *r = create(&s, N, 1);
    int first = solve_affine(r, A, b1, N);
    int second = solve_affine(r, A, b2, N);
    assert_true(first <= N + 2);
    assert_true(second < first);
    cpl_relax_free(r);
}

static void test_divergence_reported(void **state)
{
    (void)state;
    cpl_relax *r = make("constant", 1.0, 1, 1);
    double x = 0.0, out = INFINITY, alpha;
    nc_error err;
    assert_int_equal(cpl_relax_update(r, &x, &out, &x, &alpha, &err), -1);
    assert_non_null(strstr(err.message, "non-finite"));
    cpl_relax_free(r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant_and_none),
        cmocka_unit_test(test_aitken_exact_on_scalar_affine_map),
        cmocka_unit_test(test_aitken_first_iteration_cap_and_sign),
        cmocka_unit_test(test_aitken_first_iteration_cap_by_regime),
        cmocka_unit_test(test_aitken_clipping_and_zero_denominator),
        cmocka_unit_test(test_aitken_restart_breaks_onoff_cycle),
        cmocka_unit_test(test_aitken_restart_inactive_when_converging),
        cmocka_unit_test(test_aitken_restart_on_repeated_input),
        cmocka_unit_test(test_aitken_newton_regime),
        cmocka_unit_test(test_aitken_newton_rule_steps_aside),
        cmocka_unit_test(test_iqn_linear_in_n_plus_1_updates),
        cmocka_unit_test(test_iqn_plain_step_by_regime),
        cmocka_unit_test(test_iqn_filter_drops_dependent_columns),
        cmocka_unit_test(test_iqn_reuse_previous_steps),
        cmocka_unit_test(test_divergence_reported),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
