/* fem_gmres — see fem_gmres.h. Arnoldi with modified Gram–Schmidt, Givens rotations on the
 * Hessenberg matrix (Saad & Schultz 1986), right preconditioning: the Krylov space is built
 * on A M⁻¹ and the solution is x = M⁻¹ V y. */
#include "fem_gmres.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int fem_gmres_reserve(fem_gmres *g, int n, int max_iterations, nc_error *err)
{
    if (g->V && g->n == n && g->max_iterations >= max_iterations) return 0;
    fem_gmres_free(g);
    size_t m = (size_t)max_iterations, nn = (size_t)(n > 0 ? n : 1);
    g->V = malloc((m + 1) * nn * sizeof(double));
    g->H = calloc((m + 1) * m, sizeof(double));
    g->cs = malloc(m * sizeof(double));
    g->sn = malloc(m * sizeof(double));
    g->g = malloc((m + 1) * sizeof(double));
    g->y = malloc(m * sizeof(double));
    g->z = malloc(nn * sizeof(double));
    if (!g->V || !g->H || !g->cs || !g->sn || !g->g || !g->y || !g->z) {
        fem_gmres_free(g);
        return nc_error_set(err, 1, "out of memory for GMRES on %d equations", n);
    }
    g->n = n;
    g->max_iterations = max_iterations;
    return 0;
}

void fem_gmres_free(fem_gmres *g)
{
    free(g->V); free(g->H); free(g->cs); free(g->sn); free(g->g); free(g->y); free(g->z);
    memset(g, 0, sizeof *g);
}

/* a·b in four partial sums: one sum would wait for each addition before the next (the
 * orthogonalisation was the FEM's largest single cost on the MEL test) */
static double dot(const double *a, const double *b, int n)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    int i = 0;
    for (; i + 4 <= n; i += 4) {
        s0 += a[i] * b[i];
        s1 += a[i + 1] * b[i + 1];
        s2 += a[i + 2] * b[i + 2];
        s3 += a[i + 3] * b[i + 3];
    }
    for (; i < n; i++) s0 += a[i] * b[i];
    return (s0 + s1) + (s2 + s3);
}

/* One step of modified Gram–Schmidt fused with the next one's projection: w -= h v, then
 * returns w·next with the updated w (next may be w itself: the norm²), in one pass over w. */
static double subtract_then_dot(double *w, double h, const double *v, const double *next, int n)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    int i = 0;
    for (; i + 4 <= n; i += 4) {
        w[i] -= h * v[i];
        w[i + 1] -= h * v[i + 1];
        w[i + 2] -= h * v[i + 2];
        w[i + 3] -= h * v[i + 3];
        s0 += w[i] * next[i];
        s1 += w[i + 1] * next[i + 1];
        s2 += w[i + 2] * next[i + 2];
        s3 += w[i + 3] * next[i + 3];
    }
    for (; i < n; i++) {
        w[i] -= h * v[i];
        s0 += w[i] * next[i];
    }
    return (s0 + s1) + (s2 + s3);
}

int fem_gmres_solve(fem_gmres *g, fem_gmres_apply apply_A, fem_gmres_apply apply_Minv, void *ctx,
                    const double *b, double *x, double tol, int max_iterations, int *iterations,
                    nc_error *err)
{
    const int n = g->n, ld = g->max_iterations + 1;
    const int m = max_iterations < g->max_iterations ? max_iterations : g->max_iterations;
    double *V = g->V, *H = g->H;
    *iterations = 0;
    memset(x, 0, (size_t)n * sizeof *x);
    const double beta = sqrt(dot(b, b, n));
    if (beta == 0.0) return 0;
    for (int i = 0; i < n; i++) V[i] = b[i] / beta;
    memset(g->g, 0, (size_t)(m + 1) * sizeof(double));
    g->g[0] = beta;
    int k = 0, converged = 0;
    while (k < m) {
        double *w = V + (size_t)(k + 1) * n;
        if (apply_Minv(ctx, V + (size_t)k * n, g->z, err) || apply_A(ctx, g->z, w, err)) return -1;
        double *h = H + (size_t)k * ld;
        h[0] = dot(w, V, n);
        double norm2 = 0.0;
        for (int i = 0; i <= k; i++) {
            const double *following = i < k ? V + (size_t)(i + 1) * n : w;
            const double s = subtract_then_dot(w, h[i], V + (size_t)i * n, following, n);
            if (i < k) h[i + 1] = s;
            else norm2 = s;
        }
        const double next = sqrt(norm2);
        h[k + 1] = next;
        for (int i = 0; i < k; i++) {
            double t = g->cs[i] * h[i] + g->sn[i] * h[i + 1];
            h[i + 1] = -g->sn[i] * h[i] + g->cs[i] * h[i + 1];
            h[i] = t;
        }
        const double d = hypot(h[k], h[k + 1]);
        if (!(d > 0.0) || !isfinite(d)) break;   /* singular or overflowed: keep what we have */
        g->cs[k] = h[k] / d;
        g->sn[k] = h[k + 1] / d;
        h[k] = d;
        h[k + 1] = 0.0;
        g->g[k + 1] = -g->sn[k] * g->g[k];
        g->g[k] = g->cs[k] * g->g[k];
        k++;
        if (fabs(g->g[k]) <= tol * beta || next == 0.0) {
            converged = 1;
            break;
        }
        for (int q = 0; q < n; q++) w[q] /= next;
    }
    *iterations = k;
    /* y = H⁻¹ g (upper triangular k x k), then x = M⁻¹ (V y) */
    for (int i = k - 1; i >= 0; i--) {
        double s = g->g[i];
        for (int j = i + 1; j < k; j++) s -= H[(size_t)j * ld + i] * g->y[j];
        g->y[i] = s / H[(size_t)i * ld + i];
    }
    double *sum = V + (size_t)k * n;   /* column k is free once the loop is over */
    memset(sum, 0, (size_t)n * sizeof *sum);
    for (int j = 0; j < k; j++)
        for (int q = 0; q < n; q++) sum[q] += g->y[j] * V[(size_t)j * n + q];
    if (k > 0 && apply_Minv(ctx, sum, x, err)) return -1;
    return converged ? 0 : 1;
}
