/* test_gmres — GMRES with right preconditioning (fem_gmres.h) on dense systems whose
 * solution is known: A x = b with x chosen first, b = A x.
 *  - an unsymmetric, non-normal 12 x 12 matrix without preconditioning: the exact solution
 *    within 12 iterations (GMRES is exact after n steps), 1e-10 relative;
 *  - A = S + W, S symmetric positive definite, W skew and nonzero only on 3 of the 40
 *    unknowns (a contact's skew part), preconditioned by S⁻¹: converged within rank(W) + 1 = 3
 *    iterations, as the FEM's Newton step relies on;
 *  - an iteration limit below what is needed returns 1 with the least-squares iterate, whose
 *    residual is below ‖b‖ (GMRES never increases it);
 *  - b = 0 gives x = 0 in no iteration. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../../fem_solver/fem_gmres.h"

#define NMAX 40

typedef struct dense {
    int n;
    double A[NMAX][NMAX];
    double Minv[NMAX][NMAX];   /* the preconditioner (identity when not set) */
} dense;

static void matvec(const double M[NMAX][NMAX], int n, const double *x, double *y)
{
    for (int i = 0; i < n; i++) {
        y[i] = 0;
        for (int j = 0; j < n; j++) y[i] += M[i][j] * x[j];
    }
}

static int apply_A(void *ctx, const double *x, double *y, nc_error *err)
{
    (void)err;
    const dense *d = ctx;
    matvec(d->A, d->n, x, y);
    return 0;
}

static int apply_Minv(void *ctx, const double *x, double *y, nc_error *err)
{
    (void)err;
    const dense *d = ctx;
    matvec(d->Minv, d->n, x, y);
    return 0;
}

static void identity(double M[NMAX][NMAX], int n)
{
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) M[i][j] = i == j;
}

/* the inverse of a symmetric positive definite n x n matrix, by Gauss–Jordan */
static void invert(double S[NMAX][NMAX], double R[NMAX][NMAX], int n)
{
    static double W[NMAX][2 * NMAX];
    for (int i = 0; i < n; i++)
        for (int j = 0; j < 2 * n; j++) W[i][j] = j < n ? S[i][j] : (j - n == i);
    for (int c = 0; c < n; c++) {
        double p = W[c][c];
        for (int j = 0; j < 2 * n; j++) W[c][j] /= p;
        for (int i = 0; i < n; i++)
            if (i != c) {
                double f = W[i][c];
                for (int j = 0; j < 2 * n; j++) W[i][j] -= f * W[c][j];
            }
    }
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) R[i][j] = W[i][n + j];
}

static void known_rhs(const dense *d, double *x, double *b)
{
    nc_error err;
    for (int i = 0; i < d->n; i++) x[i] = sin(1.0 + 0.7 * i) + 0.1 * i;
    apply_A((void *)d, x, b, &err);
}

static void test_unsymmetric_unpreconditioned(void **state)
{
    (void)state;
    static dense d;
    d.n = 12;
    for (int i = 0; i < d.n; i++)
        for (int j = 0; j < d.n; j++)
            d.A[i][j] = (i == j ? 4.0 + i : 0.0) + (j == i + 1 ? 3.0 : 0.0) + (j == i - 2 ? -1.5 : 0.0) +
                        0.1 * cos(i + 2.0 * j);
    identity(d.Minv, d.n);
    double x[NMAX], b[NMAX], got[NMAX];
    known_rhs(&d, x, b);
    fem_gmres g = {0};
    nc_error err;
    assert_int_equal(fem_gmres_reserve(&g, d.n, 20, &err), 0);
    int its = -1;
    assert_int_equal(fem_gmres_solve(&g, apply_A, apply_Minv, &d, b, got, 1e-13, 20, &its, &err), 0);
    assert_true(its >= 1 && its <= d.n);
    for (int i = 0; i < d.n; i++) assert_near(got[i], x[i], 1e-10 * (fabs(x[i]) + 1.0));
    fem_gmres_free(&g);
}

static void test_skew_on_few_unknowns(void **state)
{
    (void)state;
    static dense d;
    static double S[NMAX][NMAX];
    d.n = NMAX;
    /* S: a stiffness-like chain (tridiagonal, diagonally dominant) */
    for (int i = 0; i < d.n; i++)
        for (int j = 0; j < d.n; j++) S[i][j] = i == j ? 3.0 + 0.01 * i : (abs(i - j) == 1 ? -1.0 : 0.0);
    /* W: skew, on the unknowns 10, 11, 12 only (rank 2, as every 3x3 skew matrix) */
    double w[3][3] = {{0, 0.8, -0.5}, {-0.8, 0, 1.3}, {0.5, -1.3, 0}};
    for (int i = 0; i < d.n; i++)
        for (int j = 0; j < d.n; j++) d.A[i][j] = S[i][j];
    for (int a = 0; a < 3; a++)
        for (int c = 0; c < 3; c++) d.A[10 + a][10 + c] += w[a][c];
    invert(S, d.Minv, d.n);
    double x[NMAX], b[NMAX], got[NMAX];
    known_rhs(&d, x, b);
    fem_gmres g = {0};
    nc_error err;
    assert_int_equal(fem_gmres_reserve(&g, d.n, 30, &err), 0);
    int its = -1;
    assert_int_equal(fem_gmres_solve(&g, apply_A, apply_Minv, &d, b, got, 1e-12, 30, &its, &err), 0);
    assert_true(its >= 1 && its <= 3);
    for (int i = 0; i < d.n; i++) assert_near(got[i], x[i], 1e-10 * (fabs(x[i]) + 1.0));

    /* one iteration is not enough: 1, and the iterate reduces the residual */
    assert_int_equal(fem_gmres_solve(&g, apply_A, apply_Minv, &d, b, got, 1e-12, 1, &its, &err), 1);
    assert_int_equal(its, 1);
    double Ax[NMAX], r2 = 0, b2 = 0;
    apply_A(&d, got, Ax, &err);
    for (int i = 0; i < d.n; i++) {
        r2 += (b[i] - Ax[i]) * (b[i] - Ax[i]);
        b2 += b[i] * b[i];
    }
    assert_true(r2 < b2);

    /* b = 0 */
    memset(b, 0, sizeof b);
    got[0] = 1.0;
    assert_int_equal(fem_gmres_solve(&g, apply_A, apply_Minv, &d, b, got, 1e-12, 30, &its, &err), 0);
    assert_int_equal(its, 0);
    for (int i = 0; i < d.n; i++) assert_true(got[i] == 0.0);
    fem_gmres_free(&g);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_unsymmetric_unpreconditioned),
        cmocka_unit_test(test_skew_on_few_unknowns),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
