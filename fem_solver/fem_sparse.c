/* fem_sparse — fixed-pattern assembly target and CHOLMOD/UMFPACK factorisation
 * (see fem_sparse.h). */
#include "fem_sparse.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <umfpack.h>

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* slot of (row r, column c), r <= c, by binary search in column c (build time only) */
static int find_slot(const fem_sparse *s, int r, int c)
{
    int lo = s->colptr[c], hi = s->colptr[c + 1] - 1;
    while (lo <= hi) {
        int mid = (lo + hi) / 2;
        if (s->rowind[mid] == r) return mid;
        if (s->rowind[mid] < r) lo = mid + 1; else hi = mid - 1;
    }
    return -1;
}

int fem_sparse_build(fem_sparse *s, int n, int n_elem, const int *elem_eq, int *slot_map,
                     int mode, nc_error *err)
{
    memset(s, 0, sizeof *s);
    s->n = n;
    if (n <= 0) return nc_error_set(err, 1, "the model has no free degree of freedom (everything is fixed)");
    size_t cap = (size_t)n + 21 * (size_t)n_elem;
    uint64_t *keys = malloc(cap * sizeof *keys);
    if (!keys) return nc_error_set(err, 1, "out of memory building the sparse pattern");
    size_t nk = 0;
    for (int i = 0; i < n; i++) keys[nk++] = ((uint64_t)i << 32) | (uint32_t)i;
    for (int e = 0; e < n_elem; e++) {
        const int *q = elem_eq + 6 * e;
        for (int a = 0; a < 6; a++)
            for (int b = a + 1; b < 6; b++) {
                if (q[a] < 0 || q[b] < 0) continue;
                int r = q[a] < q[b] ? q[a] : q[b], c = q[a] < q[b] ? q[b] : q[a];
                keys[nk++] = ((uint64_t)c << 32) | (uint32_t)r;
            }
    }
    qsort(keys, nk, sizeof *keys, cmp_u64);
    size_t nu = 0;
    for (size_t i = 0; i < nk; i++)
        if (nu == 0 || keys[i] != keys[nu - 1]) keys[nu++] = keys[i];
    s->nnz = (int)nu;

    cholmod_start(&s->c);
    s->started = 1;
    s->c.print = 0;
    s->c.error_handler = NULL;
    s->A = cholmod_allocate_sparse((size_t)n, (size_t)n, nu, 1, 1, 1, CHOLMOD_REAL, &s->c);
    s->diag = malloc((size_t)n * sizeof *s->diag);
    s->factor_x = malloc(nu * sizeof *s->factor_x);
    s->saved_factor_x = malloc(nu * sizeof *s->saved_factor_x);
    if (!s->A || !s->diag || !s->factor_x || !s->saved_factor_x) {
        free(keys);
        return nc_error_set(err, 1, "out of memory allocating a %d x %d sparse matrix", n, n);
    }
    s->colptr = s->A->p;
    s->rowind = s->A->i;
    s->x = s->A->x;
    for (int c = 0; c <= n; c++) s->colptr[c] = 0;
    for (size_t i = 0; i < nu; i++) {
        s->colptr[(keys[i] >> 32) + 1]++;
        s->rowind[i] = (int)(keys[i] & 0xffffffffu);
    }
    for (int c = 0; c < n; c++) s->colptr[c + 1] += s->colptr[c];
    free(keys);
    memset(s->x, 0, nu * sizeof *s->x);
    for (int i = 0; i < n; i++) s->diag[i] = find_slot(s, i, i);

    for (int e = 0; e < n_elem; e++) {
        const int *q = elem_eq + 6 * e;
        for (int a = 0; a < 6; a++)
            for (int b = 0; b < 6; b++) {
                int slot = -1;
                if (q[a] >= 0 && q[b] >= 0 && q[a] <= q[b]) slot = find_slot(s, q[a], q[b]);
                slot_map[36 * e + 6 * a + b] = slot;
            }
    }

    s->c.supernodal = mode == 1 ? CHOLMOD_SIMPLICIAL : mode == 2 ? CHOLMOD_SUPERNODAL : CHOLMOD_AUTO;
    s->auto_mode = mode == 0;
    s->L = cholmod_analyze(s->A, &s->c);
    s->B = cholmod_zeros((size_t)n, 1, CHOLMOD_REAL, &s->c);
    if (!s->L || !s->B || s->c.status < CHOLMOD_OK)
        return nc_error_set(err, 1, "CHOLMOD could not analyse the %d x %d system (status %d)", n,
                            n, s->c.status);
    return 0;
}

/* The full (both triangles) pattern for UMFPACK, built the first time it is needed. */
static int build_full(fem_sparse *s, nc_error *err)
{
    int n = s->n;
    s->full_nnz = 2 * s->nnz - n;
    s->full_colptr = calloc((size_t)n + 1, sizeof(int));
    s->full_rowind = malloc((size_t)s->full_nnz * sizeof(int));
    s->full_from = malloc((size_t)s->full_nnz * sizeof(int));
    s->full_x = malloc((size_t)s->full_nnz * sizeof(double));
    int *next = malloc((size_t)n * sizeof(int));
    if (!s->full_colptr || !s->full_rowind || !s->full_from || !s->full_x || !next) {
        free(next);
        return nc_error_set(err, 1, "out of memory for the LU fallback");
    }
    for (int c = 0; c < n; c++)
        for (int k = s->colptr[c]; k < s->colptr[c + 1]; k++) {
            int r = s->rowind[k];
            s->full_colptr[c + 1]++;
            if (r != c) s->full_colptr[r + 1]++;
        }
    for (int c = 0; c < n; c++) s->full_colptr[c + 1] += s->full_colptr[c];
    for (int c = 0; c < n; c++) next[c] = s->full_colptr[c];
    /* columns filled in increasing column order keep row indices sorted */
    for (int c = 0; c < n; c++)
        for (int k = s->colptr[c]; k < s->colptr[c + 1]; k++) {
            int r = s->rowind[k];
            s->full_rowind[next[c]] = r;
            s->full_from[next[c]++] = k;
            if (r != c) {
                s->full_rowind[next[r]] = c;
                s->full_from[next[r]++] = k;
            }
        }
    free(next);
    /* rows within each column: upper part (r < c) came first in order, lower part (r > c,
     * added while scanning later columns) after, also in order, so each column is sorted. */
    double control[UMFPACK_CONTROL], info[UMFPACK_INFO];
    umfpack_di_defaults(control);
    for (int k = 0; k < s->full_nnz; k++) s->full_x[k] = s->x[s->full_from[k]];
    /* the pattern alone (no values): the analysis then depends on nothing but the pattern,
     * so a run resumed from a checkpoint rebuilds the same one */
    int status = umfpack_di_symbolic(n, n, s->full_colptr, s->full_rowind, NULL, &s->symbolic,
                                     control, info);
    if (status != UMFPACK_OK) return nc_error_set(err, 1, "UMFPACK symbolic analysis failed (status %d)", status);
    return 0;
}

int fem_sparse_factorize(fem_sparse *s, int *bad_eq, nc_error *err)
{
    *bad_eq = -1;
    s->factor_is_saved = 0;
    /* a zero diagonal is a dof nothing holds: report it before any factorisation */
    double dmax = 0;
    for (int i = 0; i < s->n; i++) dmax = fmax(dmax, fabs(s->x[s->diag[i]]));
    for (int i = 0; i < s->n; i++) {
        double d = s->x[s->diag[i]];
        if (!isfinite(d)) {
            *bad_eq = i;
            return nc_error_set(err, FEM_ERR_SINGULAR, "the system matrix has a non-finite diagonal entry");
        }
        if (fabs(d) <= 1e-14 * dmax || dmax == 0) {
            *bad_eq = i;
            return nc_error_set(err, FEM_ERR_SINGULAR, "the system matrix is singular (zero stiffness)");
        }
    }
    s->use_lu = 0;
    s->have_factor = 0;
    s->c.quick_return_if_not_posdef = 1;
    cholmod_factorize(s->A, s->L, &s->c);
    if (s->c.status == CHOLMOD_NOT_POSDEF && s->auto_mode && s->L->is_super) {
        /* Indefinite: supernodal LL^T stopped at a non-positive pivot. Simplicial LDL^T takes
         * it at about twice the time of LL^T, where UMFPACK's LU took over ten times and is
         * not kept across a restore (measured on a three-module barrier struck by a block:
         * 54 LU fallbacks in 12 ms of contact, half of the run's wall time). A model that
         * was indefinite once will be again (a rock's contact, compressed posts): the factor
         * stays LDL^T, also the saved one, so a restored step repeats the same operations. */
        if (!cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, s->L, &s->c) ||
            (s->L_saved && !cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, s->L_saved, &s->c)))
            return nc_error_set(err, 1, "CHOLMOD could not change the factor to LDL^T (status %d)",
                                s->c.status);
        s->switched_to_ldlt = 1;
        cholmod_factorize(s->A, s->L, &s->c);
    }
    if (s->c.status == CHOLMOD_OK) {
        s->have_factor = 1;
        memcpy(s->factor_x, s->x, (size_t)s->nnz * sizeof *s->x);
        return 0;
    }
    if (s->c.status != CHOLMOD_NOT_POSDEF)
        return nc_error_set(err, 1, "CHOLMOD factorisation failed (status %d)", s->c.status);
    int minor = (int)s->L->minor;
    /* not positive definite: indefinite (compressed truss) or singular; try LU */
    if (!s->symbolic && build_full(s, err)) return -1;
    for (int k = 0; k < s->full_nnz; k++) s->full_x[k] = s->x[s->full_from[k]];
    double control[UMFPACK_CONTROL], info[UMFPACK_INFO];
    umfpack_di_defaults(control);
    if (s->numeric) umfpack_di_free_numeric(&s->numeric);
    int status = umfpack_di_numeric(s->full_colptr, s->full_rowind, s->full_x, s->symbolic,
                                    &s->numeric, control, info);
    if (status == UMFPACK_WARNING_singular_matrix || status != UMFPACK_OK) {
        int *perm = s->L->Perm;
        *bad_eq = (minor >= 0 && minor < s->n && perm) ? perm[minor] : 0;
        return nc_error_set(err, FEM_ERR_SINGULAR, "the system matrix is singular (not positive definite, and LU found a zero pivot)");
    }
    s->use_lu = 1;
    s->have_factor = 1;
    s->lu_count++;
    memcpy(s->factor_x, s->x, (size_t)s->nnz * sizeof *s->x);
    return 0;
}

int fem_sparse_solve(fem_sparse *s, const double *b, double *x, nc_error *err)
{
    int n = s->n;
    if (s->use_lu) {
        double control[UMFPACK_CONTROL], info[UMFPACK_INFO];
        umfpack_di_defaults(control);
        double *bx = s->B->x;
        memcpy(bx, b, (size_t)n * sizeof *b);
        int status = umfpack_di_solve(UMFPACK_A, s->full_colptr, s->full_rowind, s->full_x, x,
                                      bx, s->numeric, control, info);
        if (status != UMFPACK_OK) return nc_error_set(err, 1, "UMFPACK solve failed (status %d)", status);
        return 0;
    }
    memcpy(s->B->x, b, (size_t)n * sizeof *b);
    if (!cholmod_solve2(CHOLMOD_A, s->L, s->B, NULL, &s->X, NULL, &s->Y, &s->E, &s->c))
        return nc_error_set(err, 1, "CHOLMOD solve failed (status %d)", s->c.status);
    memcpy(x, s->X->x, (size_t)n * sizeof *x);
    return 0;
}

int fem_sparse_save_factor(fem_sparse *s, nc_error *err)
{
    /* a step that kept the factorisation of an earlier one (modified Newton) or that ended
     * where it was restored: the saved copy already is this factor */
    if (s->factor_is_saved && s->saved_valid && s->have_factor && !s->use_lu) return 0;
    s->factor_is_saved = 0;
    if (s->L_saved) cholmod_free_factor(&s->L_saved, &s->c);
    s->saved_valid = 0;
    if (!s->have_factor || s->use_lu) return 0;
    s->L_saved = cholmod_copy_factor(s->L, &s->c);
    if (!s->L_saved) return nc_error_set(err, 1, "out of memory copying the factorisation");
    s->saved_valid = 1;
    s->factor_is_saved = 1;
    memcpy(s->saved_factor_x, s->factor_x, (size_t)s->nnz * sizeof *s->x);
    return 0;
}

int fem_sparse_restore_factor(fem_sparse *s, nc_error *err)
{
    if (!s->saved_valid) {
        s->have_factor = 0;
        return 0;
    }
    if (s->factor_is_saved && s->have_factor && !s->use_lu) return 0;   /* L is the copy */
    cholmod_factor *copy = cholmod_copy_factor(s->L_saved, &s->c);
    if (!copy) return nc_error_set(err, 1, "out of memory copying the factorisation");
    cholmod_free_factor(&s->L, &s->c);
    s->L = copy;
    s->use_lu = 0;
    s->have_factor = 1;
    s->factor_is_saved = 1;
    memcpy(s->factor_x, s->saved_factor_x, (size_t)s->nnz * sizeof *s->x);
    return 0;
}

int fem_sparse_refactor(fem_sparse *s, const double *values, const double *saved_values,
                        nc_error *err)
{
    int bad;
    size_t bytes = (size_t)s->nnz * sizeof *s->x;
    if (s->L_saved) cholmod_free_factor(&s->L_saved, &s->c);
    s->saved_valid = 0;
    s->factor_is_saved = 0;
    if (saved_values) {
        memcpy(s->x, saved_values, bytes);
        if (fem_sparse_factorize(s, &bad, err) || fem_sparse_save_factor(s, err))
            return nc_error_prefix(err, "refactorising the saved matrix");
        if (!s->saved_valid)
            return nc_error_set(err, 1, "the saved factorisation is an LU one, which is never kept");
    }
    s->have_factor = 0;
    s->use_lu = 0;
    if (values) {
        memcpy(s->x, values, bytes);
        if (fem_sparse_factorize(s, &bad, err)) return nc_error_prefix(err, "refactorising the matrix");
    }
    return 0;
}

void fem_sparse_matvec(const fem_sparse *s, const double *x, double *y)
{
    for (int i = 0; i < s->n; i++) y[i] = 0.0;
    for (int c = 0; c < s->n; c++) {
        double xc = x[c], yc = 0.0;
        for (int k = s->colptr[c]; k < s->colptr[c + 1]; k++) {
            int r = s->rowind[k];
            double a = s->x[k];
            if (r == c) {
                yc += a * xc;
            } else {
                yc += a * x[r];     /* upper entry (r, c) */
                y[r] += a * xc;     /* its mirror (c, r) */
            }
        }
        y[c] += yc;
    }
}

void fem_sparse_free(fem_sparse *s)
{
    if (!s) return;
    if (s->started) {
        cholmod_free_factor(&s->L_saved, &s->c);
        cholmod_free_factor(&s->L, &s->c);
        cholmod_free_sparse(&s->A, &s->c);
        cholmod_free_dense(&s->B, &s->c);
        cholmod_free_dense(&s->X, &s->c);
        cholmod_free_dense(&s->Y, &s->c);
        cholmod_free_dense(&s->E, &s->c);
        cholmod_finish(&s->c);
    }
    if (s->numeric) umfpack_di_free_numeric(&s->numeric);
    if (s->symbolic) umfpack_di_free_symbolic(&s->symbolic);
    free(s->diag);
    free(s->factor_x); free(s->saved_factor_x);
    free(s->full_colptr); free(s->full_rowind); free(s->full_from); free(s->full_x);
    memset(s, 0, sizeof *s);
}
