/* fem_linearisation_psd — see fem_linearisation_psd.h. */
#include "fem_linearisation_psd.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* LAPACK: eigenvalues and eigenvectors of a real symmetric matrix (column-major). */
extern void dsyev_(const char *jobz, const char *uplo, const int *n, double *a, const int *lda,
                   double *w, double *work, const int *lwork, int *info);

static int cmp_int(const void *a, const void *b)
{
    int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

static int find_root(int *parent, int i)
{
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

static int local_index(const fem_psd *p, size_t n, int node)
{
    const int *hit = bsearch(&node, p->node_list, n, sizeof *p->node_list, cmp_int);
    return (int)(hit - p->node_list);
}

static int grow(void **ptr, size_t count, size_t size)
{
    void *q = realloc(*ptr, count * size);
    if (!q) return -1;
    *ptr = q;
    return 0;
}

static int reserve_blocks(fem_psd *p, size_t n, nc_error *err)
{
    if (n <= p->cap_blocks) return 0;
    size_t cap = n > 2 * p->cap_blocks ? n : 2 * p->cap_blocks;
    if (grow((void **)&p->nodes, 2 * cap, sizeof *p->nodes) ||
        grow((void **)&p->K, 9 * cap, sizeof *p->K) || grow((void **)&p->C, 9 * cap, sizeof *p->C))
        return nc_error_set(err, 1, "interface linearisation: out of memory for %zu blocks", cap);
    p->cap_blocks = cap;
    return 0;
}

static int push_block(fem_psd *p, int i, int j, const double *K, const double *C, nc_error *err)
{
    if (reserve_blocks(p, p->n_blocks + 1, err)) return -1;
    p->nodes[2 * p->n_blocks] = i;
    p->nodes[2 * p->n_blocks + 1] = j;
    memcpy(p->K + 9 * p->n_blocks, K, 9 * sizeof *K);
    if (C) memcpy(p->C + 9 * p->n_blocks, C, 9 * sizeof *C);
    else memset(p->C + 9 * p->n_blocks, 0, 9 * sizeof *p->C);
    p->n_blocks++;
    return 0;
}

/* S (n x n, symmetric, column-major) := V max(Λ, 0) Vᵀ. Returns the number of negative
 * eigenvalues clipped, or -1 when LAPACK fails; *ratio = λ_min / λ_max. */
static int clip_negative(fem_psd *p, double *S, int n, double *ratio)
{
    int lwork = 3 * n, info = 0;
    memcpy(p->vec, S, (size_t)n * (size_t)n * sizeof *S);
    dsyev_("V", "U", &n, p->vec, &n, p->eig, p->work, &lwork, &info);
    if (info != 0) return -1;
    const double lmax = fmax(fabs(p->eig[n - 1]), fabs(p->eig[0]));
    *ratio = lmax > 0.0 ? p->eig[0] / lmax : 0.0;
    int clipped = 0;
    for (int k = 0; k < n; k++) clipped += p->eig[k] < 0.0;
    if (clipped == 0) return 0;
    memset(S, 0, (size_t)n * (size_t)n * sizeof *S);
    for (int k = 0; k < n; k++) {
        if (p->eig[k] <= 0.0) continue;
        const double *v = p->vec + (size_t)k * (size_t)n;
        for (int c = 0; c < n; c++)
            for (int r = 0; r < n; r++) S[(size_t)c * (size_t)n + (size_t)r] += p->eig[k] * v[r] * v[c];
    }
    return clipped;
}

/* The symmetric part of the blocks of one component into S (column-major, 3 nc square). */
static void assemble_symmetric(const fem_psd *p, size_t n_local, int root, const int *member_pos,
                               size_t b, const int *nodes, const double *X, double *S, int nd)
{
    memset(S, 0, (size_t)nd * (size_t)nd * sizeof *S);
    for (size_t k = 0; k < b; k++) {
        int li = local_index(p, n_local, nodes[2 * k]), lj = local_index(p, n_local, nodes[2 * k + 1]);
        if (find_root(p->parent, li) != root) continue;
        int I = 3 * member_pos[li], J = 3 * member_pos[lj];
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) {
                double x = 0.5 * X[9 * k + 3 * r + c];
                S[(size_t)(J + c) * (size_t)nd + (size_t)(I + r)] += x;   /* (I+r, J+c) */
                S[(size_t)(I + r) * (size_t)nd + (size_t)(J + c)] += x;   /* transposed */
            }
    }
}

/* The symmetric part as two half blocks per block: (i, j) K/2 and (j, i) Kᵀ/2. */
static int push_halves(fem_psd *p, const int *nodes, const double *K, const double *C, size_t k,
                       nc_error *err)
{
    double Kh[9], Kt[9], Ch[9], Ct[9];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            Kh[3 * r + c] = 0.5 * K[9 * k + 3 * r + c];
            Kt[3 * r + c] = 0.5 * K[9 * k + 3 * c + r];
            Ch[3 * r + c] = C ? 0.5 * C[9 * k + 3 * r + c] : 0.0;
            Ct[3 * r + c] = C ? 0.5 * C[9 * k + 3 * c + r] : 0.0;
        }
    if (push_block(p, nodes[2 * k], nodes[2 * k + 1], Kh, C ? Ch : NULL, err) ||
        push_block(p, nodes[2 * k + 1], nodes[2 * k], Kt, C ? Ct : NULL, err))
        return -1;
    return 0;
}

int fem_psd_project(fem_psd *p, size_t b, const int *nodes, const double *K, const double *C,
                    nc_error *err)
{
    p->n_blocks = 0;
    p->has_damping = C != NULL;
    p->last_clipped = 0;
    if (b == 0) return 0;
    /* the distinct nodes, sorted, and the components of the block graph */
    if (2 * b > p->cap_nodes) {
        if (grow((void **)&p->node_list, 2 * b, sizeof *p->node_list) ||
            grow((void **)&p->parent, 2 * b, sizeof *p->parent))
            return nc_error_set(err, 1, "interface linearisation: out of memory for %zu blocks", b);
        p->cap_nodes = 2 * b;
    }
    memcpy(p->node_list, nodes, 2 * b * sizeof *nodes);
    qsort(p->node_list, 2 * b, sizeof *p->node_list, cmp_int);
    size_t n = 0;
    for (size_t i = 0; i < 2 * b; i++)
        if (n == 0 || p->node_list[i] != p->node_list[n - 1]) p->node_list[n++] = p->node_list[i];
    for (size_t i = 0; i < n; i++) p->parent[i] = (int)i;
    for (size_t k = 0; k < b; k++) {
        int a = find_root(p->parent, local_index(p, n, nodes[2 * k]));
        int c = find_root(p->parent, local_index(p, n, nodes[2 * k + 1]));
        if (a != c) p->parent[a] = c;
    }
    int *member_pos = malloc(n * sizeof *member_pos), *members = malloc(n * sizeof *members);
    if (!member_pos || !members) {
        free(member_pos); free(members);
        return nc_error_set(err, 1, "interface linearisation: out of memory for %zu nodes", n);
    }
    int rc = 0;
    for (size_t root = 0; root < n && rc == 0; root++) {
        if (find_root(p->parent, (int)root) != (int)root) continue;
        int nc = 0;
        for (size_t i = 0; i < n; i++)
            if (find_root(p->parent, (int)i) == (int)root) {
                member_pos[i] = nc;
                members[nc++] = (int)i;
            }
        p->components++;
        if (nc > FEM_PSD_MAX_NODES) {
            /* too large for a dense eigen-decomposition: the symmetric part as it is */
            p->large_components++;
            for (size_t k = 0; k < b && rc == 0; k++)
                if (find_root(p->parent, local_index(p, n, nodes[2 * k])) == (int)root)
                    rc = push_halves(p, nodes, K, C, k, err);
            continue;
        }
        const int nd = 3 * nc;
        const size_t dense = (size_t)nd * (size_t)nd;
        if (dense > p->cap_dense) {
            if (grow((void **)&p->dense_k, dense, sizeof(double)) ||
                grow((void **)&p->dense_c, dense, sizeof(double)) ||
                grow((void **)&p->vec, dense, sizeof(double)) ||
                grow((void **)&p->eig, (size_t)nd, sizeof(double)) ||
                grow((void **)&p->work, 3 * (size_t)nd, sizeof(double))) {
                rc = nc_error_set(err, 1, "interface linearisation: out of memory for a %d x %d matrix", nd, nd);
                break;
            }
            p->cap_dense = dense;
        }
        double ratio = 0.0;
        assemble_symmetric(p, n, (int)root, member_pos, b, nodes, K, p->dense_k, nd);
        int clipped = clip_negative(p, p->dense_k, nd, &ratio);
        if (clipped >= 0 && C) {
            double ratio_c;
            assemble_symmetric(p, n, (int)root, member_pos, b, nodes, C, p->dense_c, nd);
            int clipped_c = clip_negative(p, p->dense_c, nd, &ratio_c);
            clipped = clipped_c < 0 ? -1 : clipped + clipped_c;
        }
        if (clipped < 0) {
            rc = nc_error_set(err, 1, "interface linearisation: eigen-decomposition (LAPACK dsyev) of a %d x %d block failed", nd, nd);
            break;
        }
        p->clipped_eigenvalues += clipped;
        p->last_clipped += clipped;
        if (ratio < p->most_negative_ratio) p->most_negative_ratio = ratio;
        /* every node pair of the component whose block is not zero */
        double smax = 0.0;
        for (size_t e = 0; e < dense; e++) {
            smax = fmax(smax, fabs(p->dense_k[e]));
            if (C) smax = fmax(smax, fabs(p->dense_c[e]));
        }
        for (int a = 0; a < nc && rc == 0; a++)
            for (int c = 0; c < nc && rc == 0; c++) {
                double Kb[9], Cb[9], bmax = 0.0;
                for (int r = 0; r < 3; r++)
                    for (int q = 0; q < 3; q++) {
                        size_t at = (size_t)(3 * c + q) * (size_t)nd + (size_t)(3 * a + r);
                        Kb[3 * r + q] = p->dense_k[at];
                        Cb[3 * r + q] = C ? p->dense_c[at] : 0.0;
                        bmax = fmax(bmax, fmax(fabs(Kb[3 * r + q]), fabs(Cb[3 * r + q])));
                    }
                if (!(bmax > 1e-14 * smax)) continue;
                rc = push_block(p, p->node_list[members[a]], p->node_list[members[c]], Kb,
                                C ? Cb : NULL, err);
            }
    }
    free(member_pos);
    free(members);
    return rc ? -1 : 0;
}

void fem_psd_free(fem_psd *p)
{
    if (!p) return;
    free(p->nodes); free(p->K); free(p->C);
    free(p->node_list); free(p->parent);
    free(p->dense_k); free(p->dense_c); free(p->eig); free(p->work); free(p->vec);
    memset(p, 0, sizeof *p);
}
