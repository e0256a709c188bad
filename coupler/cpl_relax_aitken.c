/* cpl_relax_aitken — Aitken dynamic relaxation factor, eq. (34):
 *   α^k = −α^{k−1} (r^{k−1})ᵀ (r^k − r^{k−1}) / ‖r^k − r^{k−1}‖²
 * computed per block (α_u, α_u̇ or α_F as in the paper), with the first-iteration rule
 * α^1 = sign(α_prev)·min(first_cap, |α_prev|) (α0 in the very first step), clipping to
 * [alpha_min, alpha_max] and a guard for a vanishing denominator (keep the previous α).
 * Optional safeguard: back to the best iterate of the step when the residual grows (header). */
#include "cpl_relax_aitken.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

int cpl_aitken_init(cpl_aitken *a, size_t n, size_t n_blocks, double alpha0, double first_cap,
                    double alpha_min, double alpha_max, nc_error *err)
{
    memset(a, 0, sizeof *a);
    if (n_blocks == 0 || n % n_blocks != 0)
        return nc_error_set(err, 1, "aitken: %zu unknowns cannot be split into %zu blocks", n,
                            n_blocks);
    a->n = n;
    a->n_blocks = n_blocks;
    a->block = n / n_blocks;
    a->alpha0 = alpha0;
    a->first_cap = first_cap;
    a->alpha_min = alpha_min;
    a->alpha_max = alpha_max;
    a->alpha = calloc(n_blocks, sizeof *a->alpha);
    a->r_prev = calloc(n + 1, sizeof *a->r_prev);
    a->x_best = calloc(n + 1, sizeof *a->x_best);
    a->r_best = calloc(n + 1, sizeof *a->r_best);
    a->alpha_best = calloc(n_blocks, sizeof *a->alpha_best);
    if (!a->alpha || !a->r_prev || !a->x_best || !a->r_best || !a->alpha_best) {
        cpl_aitken_free(a);
        return nc_error_set(err, 1, "aitken: out of memory for %zu unknowns", n);
    }
    return 0;
}

void cpl_aitken_free(cpl_aitken *a)
{
    if (!a) return;
    free(a->alpha);
    free(a->r_prev);
    free(a->x_best);
    free(a->r_best);
    free(a->alpha_best);
    memset(a, 0, sizeof *a);
}

void cpl_aitken_begin_step(cpl_aitken *a)
{
    a->have_prev = 0;
    a->have_best = 0;
}

static double clip(double x, double lo, double hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

double cpl_aitken_update(cpl_aitken *a, const double *x_in, const double *x_out,
                         double *x_next)
{
    double norm2 = 0.0;
    for (size_t i = 0; i < a->n; i++) norm2 += (x_out[i] - x_in[i]) * (x_out[i] - x_in[i]);
    if (a->restart_growth > 0.0 && a->have_best && a->have_prev &&
        !(norm2 <= a->restart_growth * a->restart_growth * a->best_norm2)) {
        /* the residual grew: back to the best iterate with half its last α */
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
    const int new_best = a->restart_growth > 0.0 && (!a->have_best || norm2 < a->best_norm2);
    if (new_best) {
        memcpy(a->x_best, x_in, a->n * sizeof *x_in); /* before x_next (may alias x_in) */
        for (size_t i = 0; i < a->n; i++) a->r_best[i] = x_out[i] - x_in[i];
        a->best_norm2 = norm2;
        a->have_best = 1;
    }
    for (size_t b = 0; b < a->n_blocks; b++) {
        const size_t o = b * a->block, m = a->block;
        double alpha;
        if (!a->have_prev) {
            /* first iteration of a step: no previous residual in this step */
            if (!a->have_alpha) {
                alpha = a->alpha0;
            } else {
                double prev = a->alpha[b];
                alpha = copysign(fmin(a->first_cap, fabs(prev)), prev);
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
            if (den > DBL_MIN && den > 1e-26 * scale) alpha = -a->alpha[b] * num / den; /* (34) */
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
    return a->alpha[0];
}
