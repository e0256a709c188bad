/* cpl_relax — relaxation of the exchanged interface data, eqs. (31)–(34), and interface
 * quasi-Newton (IQN-ILS, Degroote et al. 2009).
 *
 * The relaxed vector x is either [u; s·u̇] (algorithm 2; s = the nominal Δt so both halves
 * are lengths) or the forces F (algorithm 3). In each coupling iteration the loop hands
 * over the input it used (x^k, the previous relaxed value) and the value the solvers
 * produced from it (x̃^k); cpl_relax_update() returns the input of the next iteration.
 *   none      x^{k+1} = x̃^k
 *   constant  x^{k+1} = x^k + α r^k,  r^k = x̃^k − x^k                         (31)–(33)
 *   aitken    as constant with α^k of eq. (34), one α per block (α_u, α_u̇ or α_F); the first
 *             iteration of a step uses sign(α_prev)·min(first_cap, |α_prev|) of the previous
 *             step's last α; α is clipped to [alpha_min, alpha_max]; optional restart at the
 *             best iterate of the step when the residual grows (restart_growth)
 *   iqn-ils   x^{k+1} = x̃^k + W c,  c = argmin ‖V c + r^k‖, columns of residual (V) and
 *             output (W) differences, QR filter, columns of previous steps reused
 * Lifecycle per step: begin_step, update for each non-final iteration, end_step.
 */
#ifndef CPL_RELAX_H
#define CPL_RELAX_H

#include <stddef.h>
#include "nc_error.h"

typedef enum {
    CPL_RELAX_NONE = 0,
    CPL_RELAX_CONSTANT,
    CPL_RELAX_AITKEN,
    CPL_RELAX_IQN_ILS
} cpl_relax_method;

typedef struct cpl_relax_settings {
    cpl_relax_method method;
    double alpha;           /* constant α; Aitken α of the very first iteration; IQN α of a
                               plain relaxation step (no columns yet) */
    double first_cap;       /* Aitken: cap of |α| in the first iteration of a step */
    double alpha_min;       /* Aitken: clipping range of α */
    double alpha_max;
    double restart_growth;  /* Aitken: back to the step's best iterate with half its α when
                               the residual exceeds this × the best residual (0 = off) */
    double iqn_filter;      /* IQN: drop a column whose part orthogonal to the newer
                               columns is < iqn_filter × its norm */
    int iqn_reuse_steps;    /* IQN: columns of this many previous steps are kept */
    int iqn_max_columns;    /* IQN: at most this many columns (0 = number of unknowns) */
} cpl_relax_settings;

/* Defaults: none, α = 0.5, first_cap = 0.5, clip [1e-6, 2], restart_growth 4, filter 1e-2,
 * reuse 4, max 0. */
void cpl_relax_settings_default(cpl_relax_settings *s);
const char *cpl_relax_method_name(cpl_relax_method m);

typedef struct cpl_relax cpl_relax;

/* n unknowns split into n_blocks equal contiguous blocks (Aitken computes one α per block). */
int cpl_relax_create(cpl_relax **out, const cpl_relax_settings *s, size_t n, size_t n_blocks,
                     nc_error *err);
void cpl_relax_free(cpl_relax *r);

void cpl_relax_begin_step(cpl_relax *r);
/* x_in: input of this iteration, x_out: produced value; writes the next input into x_next
 * (may alias x_in, not x_out). *alpha gets the α used (block 0), NAN for a quasi-Newton
 * update. Fails when the result is not finite (diverged iteration). */
int cpl_relax_update(cpl_relax *r, const double *x_in, const double *x_out, double *x_next,
                     double *alpha, nc_error *err);
/* Forget the last pair for the secant information (Aitken's r^{k-1}, IQN's next column):
 * used when that pair was not an evaluation of the fixed-point map (algorithm 3's first
 * iteration starts from the DEM with the predicted position, not from the relaxed force). */
void cpl_relax_forget_pair(cpl_relax *r);
/* Forget everything learnt in earlier steps (IQN columns, Aitken's last α): used after a
 * step that did not converge, whose information would mislead the next steps. */
void cpl_relax_forget_history(cpl_relax *r);
/* The step is accepted. x_in/x_out: the last pair when it was not passed to update (IQN
 * keeps its columns for the next steps), or NULL. Aitken keeps its last α regardless. */
void cpl_relax_end_step(cpl_relax *r, const double *x_in, const double *x_out);

#endif
