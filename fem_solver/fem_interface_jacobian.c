/* fem_interface_jacobian — block storage, slot map and evaluation of the coupling-force
 * linearisation (see fem_interface_jacobian.h). */
#include "fem_interface_jacobian.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* slot of (row r, column c), r <= c, in the upper-triangle pattern; -1 when not stored */
static int pattern_slot(const fem_sparse *A, int r, int c)
{
    int lo = A->colptr[c], hi = A->colptr[c + 1] - 1;
    while (lo <= hi) {
        int mid = (lo + hi) / 2;
        if (A->rowind[mid] == r) return mid;
        if (A->rowind[mid] < r) lo = mid + 1; else hi = mid - 1;
    }
    return -1;
}

int fem_ijac_pair_stored(const fem_sparse *A, const int *eq, int ni, int nj)
{
    for (int e = 0; e < 9; e++) {
        int p = eq[3 * ni + e / 3], q = eq[3 * nj + e % 3];
        if (p >= 0 && q >= 0 && (p <= q ? pattern_slot(A, p, q) : pattern_slot(A, q, p)) < 0)
            return 0;
    }
    return 1;
}

static int reserve(fem_ijac *j, int ndof, int n_blocks)
{
    if (!j->u_ref || j->ndof != ndof) {
        free(j->u_ref); free(j->v_ref); free(j->df);
        j->u_ref = malloc((size_t)ndof * sizeof(double));
        j->v_ref = malloc((size_t)ndof * sizeof(double));
        j->df = calloc((size_t)ndof, sizeof(double));
        j->ndof = ndof;
        if (!j->u_ref || !j->v_ref || !j->df) return -1;
    }
    if (n_blocks > j->cap_blocks) {
        size_t n = (size_t)n_blocks;
        int *nodes = realloc(j->nodes, 2 * n * sizeof *nodes);
        if (nodes) j->nodes = nodes;
        double *K = realloc(j->K, 9 * n * sizeof *K);
        if (K) j->K = K;
        double *C = realloc(j->C, 9 * n * sizeof *C);
        if (C) j->C = C;
        int *slot = realloc(j->slot, 9 * n * sizeof *slot);
        if (slot) j->slot = slot;
        int *row_eq = realloc(j->row_eq, 9 * n * sizeof *row_eq);
        if (row_eq) j->row_eq = row_eq;
        int *col_eq = realloc(j->col_eq, 9 * n * sizeof *col_eq);
        if (col_eq) j->col_eq = col_eq;
        double *weight = realloc(j->weight, 9 * n * sizeof *weight);
        if (weight) j->weight = weight;
        if (!nodes || !K || !C || !slot || !row_eq || !col_eq || !weight) return -1;
        j->cap_blocks = n_blocks;
    }
    return 0;
}

/* Whether the entries `value` (K or C) have a skew part on the free equations: the entries
 * (p, q) and (q, p) of one slot differ. Both are summed with opposite signs into slot_sum
 * (kept zero between calls); an exactly symmetric input (fem_linearisation_psd's parts) has
 * none. Entries of one dof pair (p == q) cannot be skew. A skew part below 1e-12 of the
 * entries is rounding and ignored. */
static int skew_in(fem_ijac *j, const double *value)
{
    const int n = 9 * j->n_blocks;
    double all2 = 0.0, skew2 = 0.0;
    for (int e = 0; e < n; e++) {
        const int slot = j->slot[e], p = j->row_eq[e], q = j->col_eq[e];
        if (slot < 0 || p == q) continue;
        j->slot_sum[slot] += (p < q ? 1.0 : -1.0) * value[e];
        all2 += value[e] * value[e];
    }
    for (int e = 0; e < n; e++) {
        const int slot = j->slot[e];
        if (slot < 0 || j->row_eq[e] == j->col_eq[e]) continue;
        skew2 += j->slot_sum[slot] * j->slot_sum[slot];
        j->slot_sum[slot] = 0.0;
    }
    return skew2 > 1e-24 * all2;
}

static int detect_skew(fem_ijac *j, int nnz)
{
    if (nnz > j->cap_slots) {
        free(j->slot_sum);
        j->slot_sum = calloc((size_t)nnz, sizeof *j->slot_sum);
        if (!j->slot_sum) { j->cap_slots = 0; return -1; }
        j->cap_slots = nnz;
    }
    j->has_skew = skew_in(j, j->K) || skew_in(j, j->C);
    return 0;
}

int fem_ijac_set(fem_ijac *j, int ndof, const int *eq, const fem_sparse *A, const double *u_ref,
                 const double *v_ref, int n_blocks, const int *block_nodes,
                 const double *K_blocks, const double *C_blocks, nc_error *err)
{
    fem_ijac_clear(j);
    if (n_blocks < 0 || (n_blocks > 0 && (!block_nodes || !K_blocks)) || !u_ref || !v_ref)
        return nc_error_set(err, 1, "interface linearisation: needs u_ref, v_ref, and nodes and K for %d blocks",
                            n_blocks);
    if (reserve(j, ndof, n_blocks))
        return nc_error_set(err, 1, "interface linearisation: out of memory for %d blocks", n_blocks);
    const int n_nodes = ndof / 3;
    for (int b = 0; b < n_blocks; b++) {
        const int ni = block_nodes[2 * b], nj = block_nodes[2 * b + 1];
        if (ni < 0 || ni >= n_nodes || nj < 0 || nj >= n_nodes)
            return nc_error_set(err, 1, "interface linearisation: block %d couples nodes (%d, %d), outside 0..%d",
                                b, ni, nj, n_nodes - 1);
        for (int e = 0; e < 9; e++) {
            double k = K_blocks[9 * b + e], c = C_blocks ? C_blocks[9 * b + e] : 0.0;
            if (!isfinite(k) || !isfinite(c))
                return nc_error_set(err, 1, "interface linearisation: block %d (nodes %d, %d) entry %d is not finite",
                                    b, ni, nj, e);
            int p = eq[3 * ni + e / 3], q = eq[3 * nj + e % 3];
            int slot = -1;
            if (p >= 0 && q >= 0) {
                slot = p <= q ? pattern_slot(A, p, q) : pattern_slot(A, q, p);
                if (slot < 0)
                    return nc_error_set(err, 1, "interface linearisation: block %d couples nodes %d and %d, which have no entry in the sparse pattern (fem_analysis_set_linearisation adds them)",
                                        b, ni, nj);
            }
            j->slot[9 * b + e] = slot;
            j->row_eq[9 * b + e] = p;
            j->col_eq[9 * b + e] = q;
            /* (p, q) and (q, p) share one upper-triangle slot: half of each is the symmetric part */
            j->weight[9 * b + e] = p == q ? 1.0 : 0.5;
        }
        j->nodes[2 * b] = ni;
        j->nodes[2 * b + 1] = nj;
    }
    if (n_blocks > 0) {   /* (no blocks: the block arrays may not exist yet) */
        memcpy(j->K, K_blocks, 9 * (size_t)n_blocks * sizeof(double));
        if (C_blocks) memcpy(j->C, C_blocks, 9 * (size_t)n_blocks * sizeof(double));
        else memset(j->C, 0, 9 * (size_t)n_blocks * sizeof(double));
    }
    memcpy(j->u_ref, u_ref, (size_t)ndof * sizeof(double));
    memcpy(j->v_ref, v_ref, (size_t)ndof * sizeof(double));
    memset(j->df, 0, (size_t)ndof * sizeof(double));
    j->n_blocks = n_blocks;
    if (detect_skew(j, A->nnz)) {
        fem_ijac_clear(j);
        return nc_error_set(err, 1, "interface linearisation: out of memory for %d matrix entries", A->nnz);
    }
    j->active = 1;
    return 0;
}

void fem_ijac_clear(fem_ijac *j)
{
    j->active = 0;
    j->n_blocks = 0;
    j->has_skew = 0;
}

void fem_ijac_force(fem_ijac *j, const double *u, const double *v)
{
    double *df = j->df;
    /* only block rows are ever written (fem_ijac_set zeroes the rest) */
    for (int b = 0; b < j->n_blocks; b++)
        for (int r = 0; r < 3; r++) df[3 * j->nodes[2 * b] + r] = 0.0;
    double scale2 = 0.0;
    for (int b = 0; b < j->n_blocks; b++) {
        const int fi = 3 * j->nodes[2 * b], mj = 3 * j->nodes[2 * b + 1];
        const double *K = j->K + 9 * b, *C = j->C + 9 * b;
        for (int r = 0; r < 3; r++) {
            double sum = 0, mag = 0;
            for (int c = 0; c < 3; c++) {
                double tk = K[3 * r + c] * (u[mj + c] - j->u_ref[mj + c]);
                double tc = v ? C[3 * r + c] * (v[mj + c] - j->v_ref[mj + c]) : 0.0;
                sum += tk + tc;
                mag += fabs(tk) + fabs(tc);
            }
            df[fi + r] -= sum;
            scale2 += mag * mag;
        }
    }
    j->force_scale_n = sqrt(scale2);
}

void fem_ijac_scatter(const fem_ijac *j, double c_k, double c_c, double *x)
{
    const int n = 9 * j->n_blocks;
    for (int e = 0; e < n; e++) {
        int slot = j->slot[e];
        if (slot >= 0) x[slot] += j->weight[e] * (c_k * j->K[e] + c_c * j->C[e]);
    }
}

double fem_ijac_rounding_n(const fem_ijac *j, double c_k, double c_c, const double *u)
{
    double sum2 = 0.0;
    for (int b = 0; b < j->n_blocks; b++) {
        const int mj = 3 * j->nodes[2 * b + 1];
        for (int r = 0; r < 3; r++) {
            if (j->row_eq[9 * b + 3 * r] < 0) continue;   /* a supported row */
            double row = 0.0;
            for (int c = 0; c < 3; c++) {
                const int e = 9 * b + 3 * r + c;
                row += fabs(c_k * j->K[e] + c_c * j->C[e]) *
                       (fabs(u[mj + c]) + fabs(j->u_ref[mj + c]));
            }
            sum2 += row * row;
        }
    }
    return DBL_EPSILON * sqrt(sum2);
}

void fem_ijac_skew_apply(const fem_ijac *j, double c_k, double c_c, const double *x, double *y)
{
    if (!j->has_skew) return;
    const int n = 9 * j->n_blocks;
    for (int e = 0; e < n; e++) {
        const int p = j->row_eq[e], q = j->col_eq[e];
        if (p < 0 || q < 0 || p == q) continue;
        /* entry (p, q) of K is entry (q, p) of K^T: (K - K^T)/2 has +K/2 at (p, q) and
         * -K/2 at (q, p) */
        const double half = 0.5 * (c_k * j->K[e] + c_c * j->C[e]);
        y[p] += half * x[q];
        y[q] -= half * x[p];
    }
}

void fem_ijac_free(fem_ijac *j)
{
    if (!j) return;
    free(j->nodes); free(j->K); free(j->C); free(j->slot); free(j->weight);
    free(j->row_eq); free(j->col_eq); free(j->slot_sum);
    free(j->u_ref); free(j->v_ref); free(j->df);
    memset(j, 0, sizeof *j);
}
