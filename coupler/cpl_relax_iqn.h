/* cpl_relax_iqn — interface quasi-Newton with an inverse Jacobian from a least-squares model
 * (IQN-ILS, Degroote, Bathe & Vierendeels 2009). Internal to cpl_relax; exposed for tests.
 *
 * Columns (newest first): V_i = r^{i+1} − r^i (residual differences), W_i = x̃^{i+1} − x̃^i
 * (output differences). Update: c = argmin ‖V c + r^k‖ via an economy QR of V built by
 * modified Gram–Schmidt; a column whose part orthogonal to the newer ones is smaller than
 * `filter` × its norm is dropped (near-dependent), then x^{k+1} = x̃^k + W c. Without any
 * column the update is a plain relaxation x^{k+1} = x^k + α r^k. Columns made in the last
 * `reuse_steps` steps are kept. For an affine problem with n unknowns x^{n+1} is exact.
 */
#ifndef CPL_RELAX_IQN_H
#define CPL_RELAX_IQN_H

#include <stddef.h>
#include "nc_error.h"

typedef struct cpl_iqn {
    size_t n;            /* unknowns */
    size_t max_cols;     /* capacity */
    size_t cols;         /* columns in use, newest first */
    double alpha;        /* plain relaxation factor (no columns) */
    double filter;
    int reuse_steps;
    long step;           /* steps begun so far */
    double *V, *W;       /* [n × max_cols] column-major */
    long *col_step;      /* [max_cols] step that made each column */
    double *r_prev, *xt_prev;   /* [n] previous iteration of this step */
    int have_prev;
    double *Q, *R, *c, *rhs;    /* work: [n × max_cols], [max_cols²], [max_cols], [max_cols] */
    size_t dropped;      /* columns removed by the filter so far (diagnostics) */
} cpl_iqn;

int cpl_iqn_init(cpl_iqn *q, size_t n, size_t max_cols, double alpha, double filter,
                 int reuse_steps, nc_error *err);
void cpl_iqn_free(cpl_iqn *q);
void cpl_iqn_begin_step(cpl_iqn *q);
/* Returns α of a plain relaxation step, NAN for a quasi-Newton update. */
double cpl_iqn_update(cpl_iqn *q, const double *x_in, const double *x_out, double *x_next);
/* Adds the last pair of the step (its column is useful for the next steps). */
void cpl_iqn_end_step(cpl_iqn *q, const double *x_in, const double *x_out);

#endif
