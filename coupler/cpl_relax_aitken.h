/* cpl_relax_aitken — Aitken Δ² dynamic relaxation, eq. (34), one α per block. Internal to
 * cpl_relax; exposed for unit tests. */
#ifndef CPL_RELAX_AITKEN_H
#define CPL_RELAX_AITKEN_H

#include <stddef.h>
#include "nc_error.h"

typedef struct cpl_aitken {
    size_t n, n_blocks, block;   /* block = n / n_blocks */
    double alpha0, first_cap, alpha_min, alpha_max;
    double *alpha;               /* [n_blocks] α of the last iteration */
    double *r_prev;              /* [n] residual of the previous iteration in this step */
    int have_prev;               /* r_prev valid (not the first iteration of the step) */
    int have_alpha;              /* α of a previous step exists */
    /* safeguard (restart_growth > 0): the iterate of the step with the smallest residual */
    double restart_growth;       /* back to the best iterate when ‖r‖ > this × ‖r_best‖; 0 off */
    double *x_best, *r_best;     /* [n] best input of this step and its residual */
    double *alpha_best;          /* [n_blocks] α applied from the best iterate */
    double best_norm2;           /* ‖r_best‖² */
    int have_best;
    long n_restarts;             /* backtracks so far (diagnostics, tests) */
} cpl_aitken;

int cpl_aitken_init(cpl_aitken *a, size_t n, size_t n_blocks, double alpha0, double first_cap,
                    double alpha_min, double alpha_max, nc_error *err);
void cpl_aitken_free(cpl_aitken *a);
void cpl_aitken_begin_step(cpl_aitken *a);
/* One relaxation: x_next = x_in + α_b (x_out − x_in) per block; returns α of block 0.
 * With restart_growth > 0: when ‖x_out − x_in‖ exceeds restart_growth × the smallest residual
 * seen in this step, the iteration goes back to that best iterate and relaxes it with half
 * the α last applied from it (x_next = x_best + α/2 r_best, repeated failures halve again);
 * the secant pair of (34) then is (best, next), which is exact again for an affine map. This
 * breaks the period-3 cycle of (34) on on/off contact: two iterates without contact make the
 * map locally constant, (34) gives α = 1, i.e. the contact-free answer, which is the deep
 * contact of the first iterate again (scripts/diagnostics/damped_contact.md). */
double cpl_aitken_update(cpl_aitken *a, const double *x_in, const double *x_out,
                         double *x_next);

#endif
