/* cpl_relax_iqn — IQN-ILS interface quasi-Newton (Degroote et al. 2009): least-squares
 * inverse-Jacobian model from residual and output differences, economy QR with a filter
 * for near-dependent columns, reuse of the columns of a few previous steps. */
#include "cpl_relax_iqn.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int cpl_iqn_init(cpl_iqn *q, size_t n, size_t max_cols, double alpha, double filter,
                 int reuse_steps, nc_error *err)
{
    memset(q, 0, sizeof *q);
    if (n == 0) return nc_error_set(err, 1, "iqn-ils: no unknowns");
    if (max_cols == 0 || max_cols > n) max_cols = n;   /* more than n columns are dependent */
    q->n = n;
    q->max_cols = max_cols;
    q->alpha = alpha;
    q->filter = filter;
    q->reuse_steps = reuse_steps;
    q->V = calloc(n * max_cols, sizeof(double));
    q->W = calloc(n * max_cols, sizeof(double));
    q->Q = calloc(n * max_cols, sizeof(double));
    q->R = calloc(max_cols * max_cols, sizeof(double));
    q->c = calloc(max_cols, sizeof(double));
    q->rhs = calloc(max_cols, sizeof(double));
    q->col_step = calloc(max_cols, sizeof(long));
    q->r_prev = calloc(n, sizeof(double));
    q->xt_prev = calloc(n, sizeof(double));
    if (!q->V || !q->W || !q->Q || !q->R || !q->c || !q->rhs || !q->col_step || !q->r_prev ||
        !q->xt_prev) {
        cpl_iqn_free(q);
        return nc_error_set(err, 1, "iqn-ils: out of memory for %zu unknowns × %zu columns",
                            n, max_cols);
    }
    return 0;
}

void cpl_iqn_free(cpl_iqn *q)
{
    if (!q) return;
    free(q->V);
    free(q->W);
    free(q->Q);
    free(q->R);
    free(q->c);
    free(q->rhs);
    free(q->col_step);
    free(q->r_prev);
    free(q->xt_prev);
    memset(q, 0, sizeof *q);
}

/* Removes column j, keeping the order of the others. */
static void remove_column(cpl_iqn *q, size_t j)
{
    const size_t n = q->n, tail = q->cols - j - 1;
    memmove(q->V + j * n, q->V + (j + 1) * n, tail * n * sizeof(double));
    memmove(q->W + j * n, q->W + (j + 1) * n, tail * n * sizeof(double));
    memmove(q->col_step + j, q->col_step + j + 1, tail * sizeof(long));
    q->cols--;
}

void cpl_iqn_begin_step(cpl_iqn *q)
{
    q->step++;
    q->have_prev = 0;
    /* keep columns of the last reuse_steps steps only (older ones describe an outdated
     * Jacobian); columns are newest first, so drop from the end */
    while (q->cols > 0 && q->step - q->col_step[q->cols - 1] > q->reuse_steps) q->cols--;
}

/* Records the differences to the previous iteration as a new first column. */
static void add_pair(cpl_iqn *q, const double *r, const double *x_out)
{
    const size_t n = q->n;
    if (q->have_prev) {
        if (q->cols == q->max_cols) q->cols--;   /* drop the oldest */
        memmove(q->V + n, q->V, q->cols * n * sizeof(double));
        memmove(q->W + n, q->W, q->cols * n * sizeof(double));
        memmove(q->col_step + 1, q->col_step, q->cols * sizeof(long));
        for (size_t i = 0; i < n; i++) {
            q->V[i] = r[i] - q->r_prev[i];
            q->W[i] = x_out[i] - q->xt_prev[i];
        }
        q->col_step[0] = q->step;
        q->cols++;
    }
    memcpy(q->r_prev, r, n * sizeof(double));
    memcpy(q->xt_prev, x_out, n * sizeof(double));
    q->have_prev = 1;
}

/* Economy QR of V by modified Gram–Schmidt (twice, for orthogonality to round-off), dropping
 * filtered columns from V and W. Leaves Q (n × cols) and upper-triangular R (cols × cols,
 * column-major with leading dimension max_cols). */
static void qr_filtered(cpl_iqn *q)
{
    const size_t n = q->n, ld = q->max_cols;
    size_t j = 0;
    while (j < q->cols) {
        double *v = q->Q + j * n;
        memcpy(v, q->V + j * n, n * sizeof(double));
        double norm0 = 0.0;
        for (size_t i = 0; i < n; i++) norm0 += v[i] * v[i];
        norm0 = sqrt(norm0);
        for (size_t l = 0; l < j; l++) q->R[l + j * ld] = 0.0;
        for (int pass = 0; pass < 2; pass++) {
            for (size_t l = 0; l < j; l++) {
                const double *ql = q->Q + l * n;
                double d = 0.0;
                for (size_t i = 0; i < n; i++) d += ql[i] * v[i];
                for (size_t i = 0; i < n; i++) v[i] -= d * ql[i];
                q->R[l + j * ld] += d;
            }
        }
        double norm = 0.0;
        for (size_t i = 0; i < n; i++) norm += v[i] * v[i];
        norm = sqrt(norm);
        if (!(norm0 > 0.0) || !(norm > q->filter * norm0) || !isfinite(norm)) {
            remove_column(q, j);   /* near-dependent on newer columns: filtered out */
            q->dropped++;
            continue;
        }
        for (size_t i = 0; i < n; i++) v[i] /= norm;
        q->R[j + j * ld] = norm;
        j++;
    }
}

double cpl_iqn_update(cpl_iqn *q, const double *x_in, const double *x_out, double *x_next)
{
    const size_t n = q->n, ld = q->max_cols;
    /* x_next holds r^k = x̃^k − x^k until the end (x_next may alias x_in, not x_out) */
    for (size_t i = 0; i < n; i++) x_next[i] = x_out[i] - x_in[i];
    add_pair(q, x_next, x_out);   /* r_prev now holds r^k */
    if (q->cols > 0) qr_filtered(q);
    if (q->cols == 0) {
        for (size_t i = 0; i < n; i++) x_next[i] = x_out[i] - (1.0 - q->alpha) * q->r_prev[i];
        return q->alpha;   /* x_in + α r = x̃ − (1 − α) r */
    }
    /* c = argmin ‖V c + r‖:  R c = −Qᵀ r */
    const size_t m = q->cols;
    for (size_t j = 0; j < m; j++) {
        const double *qj = q->Q + j * n;
        double d = 0.0;
        for (size_t i = 0; i < n; i++) d += qj[i] * q->r_prev[i];
        q->rhs[j] = -d;
    }
    for (size_t jj = m; jj-- > 0;) {
        double s = q->rhs[jj];
        for (size_t l = jj + 1; l < m; l++) s -= q->R[jj + l * ld] * q->c[l];
        q->c[jj] = s / q->R[jj + jj * ld];
    }
    for (size_t i = 0; i < n; i++) x_next[i] = x_out[i];
    for (size_t j = 0; j < m; j++) {
        const double *wj = q->W + j * n, cj = q->c[j];
        for (size_t i = 0; i < n; i++) x_next[i] += cj * wj[i];
    }
    return NAN;
}

void cpl_iqn_end_step(cpl_iqn *q, const double *x_in, const double *x_out)
{
    if (q->reuse_steps <= 0) return;
    /* Q's first column is scratch here: Q is rebuilt before every use */
    double *r = q->Q;
    for (size_t i = 0; i < q->n; i++) r[i] = x_out[i] - x_in[i];
    add_pair(q, r, x_out);
}
