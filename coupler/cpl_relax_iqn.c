/* cpl_relax_iqn — interface quasi-Newton with an inverse Jacobian from a least-squares model
 * (IQN-ILS, Degroote, Bathe & Vierendeels 2009).
 *
 * Columns (newest first): V_i = r^{i+1} − r^i (residual differences), W_i = x̃^{i+1} − x̃^i
 * (output differences). Update: c = argmin ‖V c + r^k‖ via an economy QR of V built by
 * modified Gram–Schmidt; a column whose part orthogonal to the newer ones is smaller than
 * `filter` × its norm is dropped (near-dependent, a QR2-type filter), then
 * x^{k+1} = x̃^k + W c. Without any column the update is a plain relaxation
 * x^{k+1} = x^k + α r^k (the common α; when none is given, 1 while the FEM solves with the
 * DEM's linearisation, whose answer is then Newton's full step, cpl_relax_set_linearised).
 * Columns made in the last `reuse_steps` steps are kept. For an affine problem with n
 * unknowns x^{n+1} is exact.
 *
 * Keys: filter, reuse_steps, max_columns. Counters: "columns", "dropped_columns".
 */
#include "cpl_relax_ops.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nc_json.h"

typedef struct iqn_settings {
    double filter;       /* drop a column whose part orthogonal to the newer columns is
                            < filter × its norm */
    int reuse_steps;     /* columns of this many previous steps are kept */
    int max_columns;     /* at most this many columns (0 = number of unknowns) */
} iqn_settings;
_Static_assert(sizeof(iqn_settings) <= CPL_RELAX_PARAMS_SIZE, "iqn-ils settings too large");

typedef struct iqn_state {
    size_t n;            /* unknowns */
    size_t max_cols;     /* capacity */
    size_t cols;         /* columns in use, newest first */
    double alpha;        /* plain relaxation factor (no columns) */
    int alpha_given;     /* ... from the file; else 1 while linearised */
    int linearised;      /* the FEM solves with the DEM's linearisation */
    double filter;
    int reuse_steps;
    long step;           /* steps begun so far */
    double *V, *W;       /* [n × max_cols] column-major */
    long *col_step;      /* [max_cols] step that made each column */
    double *r_prev, *xt_prev;   /* [n] previous iteration of this step */
    int have_prev;
    double *Q, *R, *c, *rhs;    /* work: [n × max_cols], [max_cols²], [max_cols], [max_cols] */
    size_t dropped;      /* columns removed by the filter so far (diagnostics) */
} iqn_state;

static const char *const iqn_keys[] = {"filter", "reuse_steps", "max_columns", NULL};

static iqn_settings settings_of(const cpl_relax_settings *s)
{
    iqn_settings p;
    memcpy(&p, s->params, sizeof p);
    return p;
}

static void iqn_defaults(cpl_relax_settings *s)
{
    const iqn_settings p = {.filter = 1e-2,   /* "QR2" filter limit commonly used */
                            .reuse_steps = 4, .max_columns = 0};
    memcpy(s->params, &p, sizeof p);
}

static int iqn_parse(cpl_relax_settings *s, const cJSON *obj, const char *where,
                     nc_error *err)
{
    iqn_settings p = settings_of(s);
    long reuse = p.reuse_steps, cols = p.max_columns;
    if (nc_json_number_range_opt(obj, where, "filter", p.filter, 1e-16, 0.5, &p.filter,
                                 err) ||
        nc_json_int_opt(obj, where, "reuse_steps", reuse, 0, 100, &reuse, err) ||
        nc_json_int_opt(obj, where, "max_columns", cols, 0, 100000, &cols, err))
        return -1;
    p.reuse_steps = (int)reuse;
    p.max_columns = (int)cols;
    memcpy(s->params, &p, sizeof p);
    return 0;
}

static int iqn_check(const cpl_relax_settings *s, const char *where, nc_error *err)
{
    const iqn_settings p = settings_of(s);
    if (cpl_relax_check_alpha(s, where, err)) return -1;
    if (!(p.filter > 0.0 && p.filter < 1.0))
        return nc_error_set(err, 1, "%s: filter must be in (0, 1), got %g", where, p.filter);
    return 0;
}

static int iqn_get(const cpl_relax_settings *s, const char *key, double *value)
{
    const iqn_settings p = settings_of(s);
    const double values[] = {p.filter, p.reuse_steps, p.max_columns};
    for (size_t i = 0; iqn_keys[i]; i++)
        if (strcmp(key, iqn_keys[i]) == 0) {
            *value = values[i];
            return 0;
        }
    return -1;
}

static void iqn_free(void *state)
{
    iqn_state *q = state;
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
    free(q);
}

static int iqn_create(void **state, const cpl_relax_settings *s, size_t n, size_t n_blocks,
                      nc_error *err)
{
    (void)n_blocks;   /* works on the whole vector */
    const iqn_settings p = settings_of(s);
    if (n == 0) return nc_error_set(err, 1, "iqn-ils: no unknowns");
    size_t max_cols = p.max_columns > 0 ? (size_t)p.max_columns : 0;
    if (max_cols == 0 || max_cols > n) max_cols = n;   /* more than n columns are dependent */
    iqn_state *q = calloc(1, sizeof *q);
    if (!q) return nc_error_set(err, 1, "iqn-ils: out of memory");
    q->n = n;
    q->max_cols = max_cols;
    q->alpha = s->alpha;
    q->alpha_given = s->alpha_given;
    q->filter = p.filter;
    q->reuse_steps = p.reuse_steps;
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
        iqn_free(q);
        return nc_error_set(err, 1, "iqn-ils: out of memory for %zu unknowns × %zu columns",
                            n, max_cols);
    }
    *state = q;
    return 0;
}

/* Removes column j, keeping the order of the others. */
static void remove_column(iqn_state *q, size_t j)
{
    const size_t n = q->n, tail = q->cols - j - 1;
    memmove(q->V + j * n, q->V + (j + 1) * n, tail * n * sizeof(double));
    memmove(q->W + j * n, q->W + (j + 1) * n, tail * n * sizeof(double));
    memmove(q->col_step + j, q->col_step + j + 1, tail * sizeof(long));
    q->cols--;
}

static void iqn_begin_step(void *state)
{
    iqn_state *q = state;
    q->step++;
    q->have_prev = 0;
    /* keep columns of the last reuse_steps steps only (older ones describe an outdated
     * Jacobian); columns are newest first, so drop from the end */
    while (q->cols > 0 && q->step - q->col_step[q->cols - 1] > q->reuse_steps) q->cols--;
}

/* Records the differences to the previous iteration as a new first column. */
static void add_pair(iqn_state *q, const double *r, const double *x_out)
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
static void qr_filtered(iqn_state *q)
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

static double iqn_update(void *state, const double *x_in, const double *x_out,
                         double *x_next)
{
    iqn_state *q = state;
    const size_t n = q->n, ld = q->max_cols;
    /* x_next holds r^k = x̃^k − x^k until the end (x_next may alias x_in, not x_out) */
    for (size_t i = 0; i < n; i++) x_next[i] = x_out[i] - x_in[i];
    add_pair(q, x_next, x_out);   /* r_prev now holds r^k */
    if (q->cols > 0) qr_filtered(q);
    if (q->cols == 0) {
        const double alpha = q->linearised && !q->alpha_given ? 1.0 : q->alpha;
        for (size_t i = 0; i < n; i++) x_next[i] = x_out[i] - (1.0 - alpha) * q->r_prev[i];
        return alpha;   /* x_in + α r = x̃ − (1 − α) r */
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

static void iqn_end_step(void *state, const double *x_in, const double *x_out)
{
    iqn_state *q = state;
    if (!x_in || !x_out || q->reuse_steps <= 0) return;
    /* Q's first column is scratch here: Q is rebuilt before every use */
    double *r = q->Q;
    for (size_t i = 0; i < q->n; i++) r[i] = x_out[i] - x_in[i];
    add_pair(q, r, x_out);
}

static void iqn_forget(void *state, cpl_relax_forget_level level)
{
    iqn_state *q = state;
    q->have_prev = 0;
    if (level == CPL_RELAX_FORGET_HISTORY) q->cols = 0;
}

static int iqn_counter(const void *state, const char *name, double *value)
{
    const iqn_state *q = state;
    if (strcmp(name, "columns") == 0) *value = (double)q->cols;
    else if (strcmp(name, "dropped_columns") == 0) *value = (double)q->dropped;
    else return -1;
    return 0;
}

/* the V/W columns kept across steps with the steps that made them, the last pair, the
 * counters; the QR work arrays too (rebuilt before use, saved so nothing is left out) */
static void iqn_checkpoint(void *state, cpl_ckpt_table *t, const char *prefix)
{
    iqn_state *q = state;
    const size_t n = q->n, m = q->max_cols;
    cpl_ckpt_size(t, prefix, "columns", &q->cols);
    cpl_ckpt_long(t, prefix, "step", &q->step);
    cpl_ckpt_f64(t, prefix, "V", q->V, n * m);
    cpl_ckpt_f64(t, prefix, "W", q->W, n * m);
    cpl_ckpt_add(t, prefix, "column_step", CPL_CKPT_LONG, q->col_step, m);
    cpl_ckpt_f64(t, prefix, "r_prev", q->r_prev, n);
    cpl_ckpt_f64(t, prefix, "xt_prev", q->xt_prev, n);
    cpl_ckpt_int(t, prefix, "have_prev", &q->have_prev);
    cpl_ckpt_f64(t, prefix, "Q", q->Q, n * m);
    cpl_ckpt_f64(t, prefix, "R", q->R, m * m);
    cpl_ckpt_f64(t, prefix, "c", q->c, m);
    cpl_ckpt_f64(t, prefix, "rhs", q->rhs, m);
    cpl_ckpt_size(t, prefix, "dropped_columns", &q->dropped);
}

static void iqn_linearised(void *state, int on)
{
    iqn_state *q = state;
    q->linearised = on;
}

const cpl_relax_ops cpl_relax_iqn_ils = {
    .name = "iqn-ils",
    .keys = iqn_keys,
    .defaults = iqn_defaults,
    .parse = iqn_parse,
    .check = iqn_check,
    .get = iqn_get,
    .create = iqn_create,
    .begin_step = iqn_begin_step,
    .update = iqn_update,
    .forget = iqn_forget,
    .linearised = iqn_linearised,
    .end_step = iqn_end_step,
    .counter = iqn_counter,
    .checkpoint = iqn_checkpoint,
    .free = iqn_free,
};
