/* cpl_relax_aitken — Aitken dynamic relaxation factor, eq. (34):
 *   α^k = −α^{k−1} (r^{k−1})ᵀ (r^k − r^{k−1}) / ‖r^k − r^{k−1}‖²
 * computed per block (α_u, α_u̇ or α_F as in the paper), then x^{k+1} = x^k + α^k r^k,
 * eqs. (31)–(33). The first iteration of a step uses α^1 = sign(α_prev)·min(first_cap,
 * |α_prev|) of the previous step's last α (the common α in the very first step); α is
 * clipped to [alpha_min, alpha_max]; a vanishing denominator keeps the previous α. Without a
 * given first_iteration_cap it is 1 while Newton's regime acts (below) and 0.5 otherwise.
 *
 * Safeguard (restart_growth > 0): when ‖x_out − x_in‖ exceeds restart_growth × the smallest
 * residual seen in this step, the iteration goes back to that best iterate and relaxes it
 * with half the α last applied from it (x_next = x_best + α/2 r_best, repeated failures
 * halve again); the secant pair of eq. (34) then is (best, next), which is exact again for an
 * affine map. This breaks the period-3 cycle of eq. (34) on on/off contact: two iterates
 * without contact make the map locally constant, eq. (34) gives α = 1, i.e. the contact-free
 * answer, which is the deep contact of the first iterate again (docs/notes/damped_contact.md).
 * The same restart is taken when the next input would repeat one of the step's last
 * AITKEN_RECENT inputs (within 1e-3 of the step to it): on a contact law with a kink the map
 * is locally constant on one side, eq. (34) gives α = 1 there whether or not the residual
 * grew, and the iteration would evaluate a point whose answer it already knows.
 *
 * Newton's regime (newton_contraction θ > 0, only while the FEM solves with the DEM's
 * linearisation, cpl_relax_set_linearised): the produced value is then Newton's step from
 * the input, and α = 1 is taken whenever ‖r^k‖ ≤ θ ‖r^{k−1}‖, and min(1, first_cap) (1
 * without a given cap: Newton's full step from the predictor) in an iteration without a
 * previous residual (a step's first, or the first after the loop made
 * the relaxation forget its pair: contact backtracking) instead of α0 or the previous α;
 * eq. (34) and the safeguard act otherwise (after a restart r^{k−1} is the best residual).
 * With α ≠ 1 a quadratically converging iteration keeps |1 − α| of each residual (eq. (34)
 * gives α − 1 of the order of the last contraction), i.e. it converges linearly
 * (docs/notes/interface_jacobian.md "Newton's regime").
 *
 * Keys: first_iteration_cap, alpha_min, alpha_max, restart_growth, newton_contraction.
 * Counters: "restarts", "full_steps".
 */
#include "cpl_relax_ops.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nc_json.h"

#define AITKEN_RECENT 4   /* inputs of the step remembered for the repeat test */

/* first_iteration_cap when none is given: Newton's full step under the linearisation (a
 * half step leaves half of the predictor's error for the next iteration), else half */
#define AITKEN_FIRST_CAP_LINEARISED 1.0
#define AITKEN_FIRST_CAP_PLAIN 0.5

typedef struct aitken_settings {
    double first_cap;        /* cap of |α| in the first iteration of a step; 0: not given
                                (AITKEN_FIRST_CAP_*) */
    double alpha_min;        /* clipping range of α */
    double alpha_max;
    double restart_growth;   /* back to the step's best iterate with half its α when the
                                residual exceeds this × the best residual (0 = off) */
    double newton_contraction; /* linearised: α = 1 while the residual contracts by this */
} aitken_settings;
_Static_assert(sizeof(aitken_settings) <= CPL_RELAX_PARAMS_SIZE,
               "aitken settings too large");

typedef struct aitken_state {
    size_t n, n_blocks, block;   /* block = n / n_blocks */
    double alpha0, first_cap, alpha_min, alpha_max;   /* first_cap 0: not given */
    double *alpha;               /* [n_blocks] α of the last iteration */
    double *r_prev;              /* [n] residual of the previous iteration in this step */
    int have_prev;               /* r_prev valid (not the first iteration of the step) */
    int have_alpha;              /* α of a previous step exists */
    /* safeguard (restart_growth > 0): the iterate of the step with the smallest residual */
    double restart_growth;       /* back to the best iterate when ‖r‖ > this × ‖r_best‖; 0 off */
    double newton_contraction;   /* linearised: α = 1 when ‖r^k‖ ≤ this × ‖r^{k−1}‖ */
    int linearised;              /* the FEM solves with the DEM's linearisation */
    long n_full;                 /* iterations whose α that rule chose, before clipping and
                                    the repeat test, since this process started
                                    (diagnostics, not checkpointed) */
    double *x_best, *r_best;     /* [n] best input of this step and its residual */
    double *alpha_best;          /* [n_blocks] α applied from the best iterate */
    double best_norm2;           /* ‖r_best‖² */
    int have_best;
    long n_restarts;             /* backtracks so far (diagnostics, tests) */
    double *recent;              /* [AITKEN_RECENT][n] the step's last inputs (safeguard on) */
    int n_recent;                /* how many of them are set */
    int next_recent;             /* the slot the next input goes to */
} aitken_state;

static const char *const aitken_keys[] = {"first_iteration_cap", "alpha_min", "alpha_max",
                                          "restart_growth", "newton_contraction", NULL};

/* The cap of the first iteration's |α|: the given one, else by the regime. */
static double first_iteration_cap(const aitken_state *a)
{
    if (a->first_cap > 0.0) return a->first_cap;
    return a->linearised && a->newton_contraction > 0.0 ? AITKEN_FIRST_CAP_LINEARISED
                                                        : AITKEN_FIRST_CAP_PLAIN;
}

static aitken_settings settings_of(const cpl_relax_settings *s)
{
    aitken_settings p;
    memcpy(&p, s->params, sizeof p);
    return p;
}

static void aitken_defaults(cpl_relax_settings *s)
{
    const aitken_settings p = {.first_cap = 0.0, .alpha_min = 1e-6, .alpha_max = 2.0,
                               .restart_growth = 4.0,   /* safeguard on (see above) */
                               .newton_contraction = 0.5};
    memcpy(s->params, &p, sizeof p);
}

static int aitken_parse(cpl_relax_settings *s, const cJSON *obj, const char *where,
                        nc_error *err)
{
    aitken_settings p = settings_of(s);
    if (nc_json_number_range_opt(obj, where, "first_iteration_cap", p.first_cap, 1e-12, 2.0,
                                 &p.first_cap, err) ||
        nc_json_number_range_opt(obj, where, "alpha_min", p.alpha_min, -2.0, 2.0,
                                 &p.alpha_min, err) ||
        nc_json_number_range_opt(obj, where, "alpha_max", p.alpha_max, -2.0, 10.0,
                                 &p.alpha_max, err) ||
        nc_json_number_range_opt(obj, where, "restart_growth", p.restart_growth, 0.0, 1e6,
                                 &p.restart_growth, err) ||
        nc_json_number_range_opt(obj, where, "newton_contraction", p.newton_contraction, 0.0,
                                 1.0, &p.newton_contraction, err))
        return -1;
    memcpy(s->params, &p, sizeof p);
    return 0;
}

static int aitken_check(const cpl_relax_settings *s, const char *where, nc_error *err)
{
    const aitken_settings p = settings_of(s);
    if (cpl_relax_check_alpha(s, where, err)) return -1;
    /* below 1 it would back-track on every iteration */
    if (p.restart_growth > 0.0 && p.restart_growth < 1.0)
        return nc_error_set(err, 1, "%s: restart_growth: expected 0 (off) or a number >= 1, "
                                    "got %g", where, p.restart_growth);
    if (!(p.alpha_min < p.alpha_max))
        return nc_error_set(err, 1, "%s: alpha_min (%g) must be smaller than alpha_max (%g)",
                            where, p.alpha_min, p.alpha_max);
    /* at 1 or more it would take α = 1 on a residual that does not shrink */
    if (!(p.newton_contraction < 1.0))
        return nc_error_set(err, 1, "%s: newton_contraction: expected a number in [0, 1), got %g",
                            where, p.newton_contraction);
    if (!(p.first_cap >= 0.0))   /* 0: not given (the parser refuses it from a file) */
        return nc_error_set(err, 1, "%s: first_iteration_cap must be > 0, got %g", where,
                            p.first_cap);
    return 0;
}

static int aitken_get(const cpl_relax_settings *s, const char *key, double *value)
{
    const aitken_settings p = settings_of(s);
    const double values[] = {p.first_cap, p.alpha_min, p.alpha_max, p.restart_growth,
                             p.newton_contraction};
    for (size_t i = 0; aitken_keys[i]; i++)
        if (strcmp(key, aitken_keys[i]) == 0) {
            *value = values[i];
            return 0;
        }
    return -1;
}

static void aitken_free(void *state)
{
    aitken_state *a = state;
    if (!a) return;
    free(a->alpha);
    free(a->r_prev);
    free(a->x_best);
    free(a->r_best);
    free(a->alpha_best);
    free(a->recent);
    free(a);
}

static int aitken_create(void **state, const cpl_relax_settings *s, size_t n, size_t n_blocks,
                         nc_error *err)
{
    const aitken_settings p = settings_of(s);
    if (n_blocks == 0 || n % n_blocks != 0)
        return nc_error_set(err, 1, "aitken: %zu unknowns cannot be split into %zu blocks", n,
                            n_blocks);
    aitken_state *a = calloc(1, sizeof *a);
    if (!a) return nc_error_set(err, 1, "aitken: out of memory");
    a->n = n;
    a->n_blocks = n_blocks;
    a->block = n / n_blocks;
    a->alpha0 = s->alpha;
    a->first_cap = p.first_cap;
    a->alpha_min = p.alpha_min;
    a->alpha_max = p.alpha_max;
    a->restart_growth = p.restart_growth;
    a->newton_contraction = p.newton_contraction;
    a->alpha = calloc(n_blocks, sizeof *a->alpha);
    a->r_prev = calloc(n + 1, sizeof *a->r_prev);
    a->x_best = calloc(n + 1, sizeof *a->x_best);
    a->r_best = calloc(n + 1, sizeof *a->r_best);
    a->alpha_best = calloc(n_blocks, sizeof *a->alpha_best);
    a->recent = calloc(AITKEN_RECENT * n + 1, sizeof *a->recent);
    if (!a->alpha || !a->r_prev || !a->x_best || !a->r_best || !a->alpha_best || !a->recent) {
        aitken_free(a);
        return nc_error_set(err, 1, "aitken: out of memory for %zu unknowns", n);
    }
    *state = a;
    return 0;
}

static void aitken_begin_step(void *state)
{
    aitken_state *a = state;
    a->have_prev = 0;
    a->have_best = 0;
    a->n_recent = 0;
    a->next_recent = 0;
}

static double clip(double x, double lo, double hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

/* The safeguard's restart: back to the best iterate with half its last α. */
static double restart_from_best(aitken_state *a, double *x_next)
{
    for (size_t b = 0; b < a->n_blocks; b++) {
        const size_t o = b * a->block, m = a->block;
        double alpha = clip(0.5 * a->alpha_best[b], a->alpha_min, a->alpha_max);
        for (size_t i = 0; i < m; i++) {
            a->r_prev[o + i] = a->r_best[o + i];
            x_next[o + i] = a->x_best[o + i] + alpha * a->r_best[o + i];
        }
        a->alpha[b] = a->alpha_best[b] = alpha;
    }
    a->n_restarts++;
    return a->alpha[0];
}

/* Whether x_next lies within 1e-3 of the step x_in → x_next from one of the remembered
 * inputs (x_in, remembered too, is a whole step away). */
static int repeats_recent(const aitken_state *a, const double *x_in, const double *x_next)
{
    double step2 = 0.0;
    for (size_t i = 0; i < a->n; i++) step2 += (x_next[i] - x_in[i]) * (x_next[i] - x_in[i]);
    if (!(step2 > 0.0)) return 0;
    for (int j = 0; j < a->n_recent; j++) {
        const double *x = a->recent + (size_t)j * a->n;
        double d2 = 0.0;
        for (size_t i = 0; i < a->n; i++) d2 += (x_next[i] - x[i]) * (x_next[i] - x[i]);
        if (d2 <= 1e-6 * step2) return 1;
    }
    return 0;
}

static void remember_input(aitken_state *a, const double *x_in)
{
    memcpy(a->recent + (size_t)a->next_recent * a->n, x_in, a->n * sizeof *x_in);
    a->next_recent = (a->next_recent + 1) % AITKEN_RECENT;
    if (a->n_recent < AITKEN_RECENT) a->n_recent++;
}

static double aitken_update(void *state, const double *x_in, const double *x_out,
                            double *x_next)
{
    aitken_state *a = state;
    double norm2 = 0.0;
    for (size_t i = 0; i < a->n; i++) norm2 += (x_out[i] - x_in[i]) * (x_out[i] - x_in[i]);
    const int safeguard = a->restart_growth > 0.0;
    if (safeguard && a->have_best && a->have_prev &&
        !(norm2 <= a->restart_growth * a->restart_growth * a->best_norm2)) {
        /* the residual grew: back to the best iterate with half its last α */
        remember_input(a, x_in);
        return restart_from_best(a, x_next);
    }
    const int new_best = safeguard && (!a->have_best || norm2 < a->best_norm2);
    if (safeguard) remember_input(a, x_in);   /* before x_next (may alias x_in) */
    if (new_best) {
        memcpy(a->x_best, x_in, a->n * sizeof *x_in); /* before x_next (may alias x_in) */
        for (size_t i = 0; i < a->n; i++) a->r_best[i] = x_out[i] - x_in[i];
        a->best_norm2 = norm2;
        a->have_best = 1;
    }
    /* Newton's regime: with the linearisation the map's slope vanishes at its fixed point,
     * and eq. (34)'s secant measures only its curvature there; an α ≠ 1 would leave
     * |1 − α| of the residual instead of a multiple of its square */
    const int rule = a->linearised && a->newton_contraction > 0.0;
    double prev2 = 0.0;
    if (rule && a->have_prev)
        for (size_t i = 0; i < a->n; i++) prev2 += a->r_prev[i] * a->r_prev[i];
    const int newton = rule && (!a->have_prev ||
                                norm2 <= a->newton_contraction * a->newton_contraction * prev2);
    if (newton) a->n_full++;
    for (size_t b = 0; b < a->n_blocks; b++) {
        const size_t o = b * a->block, m = a->block;
        double alpha;
        if (newton) {
            alpha = a->have_prev ? 1.0 : fmin(1.0, first_iteration_cap(a));
        } else if (!a->have_prev) {
            /* first iteration of a step: no previous residual in this step */
            if (!a->have_alpha) {
                alpha = a->alpha0;
            } else {
                double prev = a->alpha[b];
                alpha = copysign(fmin(first_iteration_cap(a), fabs(prev)), prev);
            }
        } else {
            double num = 0.0, den = 0.0, scale = 0.0;
            for (size_t i = 0; i < m; i++) {
                double r = x_out[o + i] - x_in[o + i];
                double dr = r - a->r_prev[o + i];
                num += a->r_prev[o + i] * dr;
                den += dr * dr;
                scale += r * r + a->r_prev[o + i] * a->r_prev[o + i];
            }
            /* guard: residual did not change (converged block or round-off only) */
            if (den > DBL_MIN && den > 1e-26 * scale) alpha = -a->alpha[b] * num / den; /* eq. (34) */
            else alpha = a->alpha[b];
            if (!isfinite(alpha)) alpha = a->alpha[b];
        }
        alpha = clip(alpha, a->alpha_min, a->alpha_max);
        for (size_t i = 0; i < m; i++) {
            double r = x_out[o + i] - x_in[o + i];
            a->r_prev[o + i] = r;
            x_next[o + i] = x_in[o + i] + alpha * r;   /* eqs. (31)–(33) */
        }
        a->alpha[b] = alpha;
        if (new_best) a->alpha_best[b] = alpha;
    }
    a->have_prev = 1;
    a->have_alpha = 1;
    /* x_next against the step's last inputs (x_in among them never matches: its distance
     * is the step itself); x_in is the newest slot, kept intact although x_next aliases it */
    const double *x_now = a->recent + (size_t)((a->next_recent + AITKEN_RECENT - 1) %
                                                AITKEN_RECENT) * a->n;
    if (safeguard && a->have_best && repeats_recent(a, x_now, x_next))
        return restart_from_best(a, x_next);
    return a->alpha[0];
}

static void aitken_forget(void *state, cpl_relax_forget_level level)
{
    aitken_state *a = state;
    a->have_prev = 0;
    if (level == CPL_RELAX_FORGET_HISTORY) a->have_alpha = 0;   /* next step starts from α0 */
}

static void aitken_linearised(void *state, int on)
{
    aitken_state *a = state;
    a->linearised = on;
}

static int aitken_counter(const void *state, const char *name, double *value)
{
    const aitken_state *a = state;
    if (strcmp(name, "restarts") == 0) *value = (double)a->n_restarts;
    else if (strcmp(name, "full_steps") == 0) *value = (double)a->n_full;
    else return -1;
    return 0;
}

/* α and r^{k-1} carried into the next step, the safeguard's best iterate, the counter */
static void aitken_checkpoint(void *state, cpl_ckpt_table *t, const char *prefix)
{
    aitken_state *a = state;
    cpl_ckpt_f64(t, prefix, "alpha", a->alpha, a->n_blocks);
    cpl_ckpt_f64(t, prefix, "r_prev", a->r_prev, a->n);
    cpl_ckpt_int(t, prefix, "have_prev", &a->have_prev);
    cpl_ckpt_int(t, prefix, "have_alpha", &a->have_alpha);
    cpl_ckpt_f64(t, prefix, "x_best", a->x_best, a->n);
    cpl_ckpt_f64(t, prefix, "r_best", a->r_best, a->n);
    cpl_ckpt_f64(t, prefix, "alpha_best", a->alpha_best, a->n_blocks);
    cpl_ckpt_f64(t, prefix, "best_norm2", &a->best_norm2, 1);
    cpl_ckpt_int(t, prefix, "have_best", &a->have_best);
    cpl_ckpt_long(t, prefix, "restarts", &a->n_restarts);
}

const cpl_relax_ops cpl_relax_aitken = {
    .name = "aitken",
    .keys = aitken_keys,
    .defaults = aitken_defaults,
    .parse = aitken_parse,
    .check = aitken_check,
    .get = aitken_get,
    .create = aitken_create,
    .begin_step = aitken_begin_step,
    .update = aitken_update,
    .forget = aitken_forget,
    .linearised = aitken_linearised,
    .counter = aitken_counter,
    .checkpoint = aitken_checkpoint,
    .free = aitken_free,
};
