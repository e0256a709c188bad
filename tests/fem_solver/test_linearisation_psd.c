/* test_linearisation_psd — the positive semi-definite part of an interface linearisation
 * (fem_linearisation_psd.h), against matrices whose projection is known in closed form:
 *  - a rock on one node, K = f' n nᵀ − (f/R)(I − n nᵀ) (normal stiffness, negative across the
 *    normal): the projection is f' n nᵀ exactly (1e-12 relative);
 *  - an unsymmetric but semi-definite symmetric part: the projection is (K + Kᵀ)/2 itself;
 *  - an edge contact coupling two nodes, [[a, −a], [−a, a]] ⊗ n nᵀ − s I: the projection
 *    keeps the eigenvalue 2a − s along (n, −n) and clips the rest;
 *  - two separate contacts are projected separately (no block between them);
 * every result checked by assembling the dense matrix and comparing entry by entry. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <string.h>

#include "../../fem_solver/fem_linearisation_psd.h"

#define NMAX 4

/* dense 3 NMAX square matrix of the blocks (node numbers < NMAX), summed */
static void assemble(size_t b, const int *nodes, const double *K, double A[3 * NMAX][3 * NMAX])
{
    memset(A, 0, sizeof(double) * 9 * NMAX * NMAX);
    for (size_t k = 0; k < b; k++)
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                A[3 * nodes[2 * k] + r][3 * nodes[2 * k + 1] + c] += K[9 * k + 3 * r + c];
}

static void assert_dense_near(double A[3 * NMAX][3 * NMAX], double B[3 * NMAX][3 * NMAX], double tol)
{
    for (int i = 0; i < 3 * NMAX; i++)
        for (int j = 0; j < 3 * NMAX; j++)
            if (fabs(A[i][j] - B[i][j]) > tol)
                fail_msg("entry (%d, %d): %.17g against %.17g (tolerance %g)", i, j, A[i][j], B[i][j], tol);
}

static void unit(double n[3])
{
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int d = 0; d < 3; d++) n[d] /= l;
}

static void test_rock_on_a_node(void **state)
{
    (void)state;
    double n[3] = {0.3, -0.2, 1.0};
    unit(n);
    const double kn = 9.1e8, f_over_r = 2.0e7;   /* f' and f / R of a granite rock */
    double K[9];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            K[3 * r + c] = kn * n[r] * n[c] - f_over_r * ((r == c) - n[r] * n[c]);
    int nodes[2] = {2, 2};
    fem_psd p = {0};
    nc_error err;
    assert_int_equal(fem_psd_project(&p, 1, nodes, K, NULL, &err), 0);
    assert_int_equal(p.last_clipped, 2);
    assert_near(p.most_negative_ratio, -f_over_r / kn, 1e-12);
    double A[3 * NMAX][3 * NMAX], E[3 * NMAX][3 * NMAX];
    assemble(p.n_blocks, p.nodes, p.K, A);
    double want[9];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) want[3 * r + c] = kn * n[r] * n[c];
    assemble(1, nodes, want, E);
    assert_dense_near(A, E, 1e-12 * kn);
    fem_psd_free(&p);
}

static void test_semidefinite_symmetric_part_is_kept(void **state)
{
    (void)state;
    /* diagonal 3e8, 2e8, 1e8 plus a skew part: (K + Kᵀ)/2 is the diagonal */
    double K[9] = {3e8, 5e7, 0.0, -5e7, 2e8, 1e7, 0.0, -1e7, 1e8};
    double D[9] = {3e8, 0, 0, 0, 2e8, 0, 0, 0, 1e8};
    double C[9] = {4e3, 0, 0, 0, 4e3, 0, 0, 0, 4e3};
    int nodes[2] = {1, 1};
    fem_psd p = {0};
    nc_error err;
    assert_int_equal(fem_psd_project(&p, 1, nodes, K, C, &err), 0);
    assert_int_equal(p.last_clipped, 0);
    assert_true(p.has_damping);
    double A[3 * NMAX][3 * NMAX], E[3 * NMAX][3 * NMAX];
    assemble(p.n_blocks, p.nodes, p.K, A);
    assemble(1, nodes, D, E);
    assert_dense_near(A, E, 1e-12 * 3e8);
    assemble(p.n_blocks, p.nodes, p.C, A);
    assemble(1, nodes, C, E);
    assert_dense_near(A, E, 1e-12 * 4e3);
    fem_psd_free(&p);
}

/* blocks of [[a, −a], [−a, a]] ⊗ n nᵀ − s I on nodes (i, j) */
static void edge_blocks(int i, int j, const double n[3], double a, double s, int *nodes, double *K)
{
    const int pairs[4][2] = {{i, i}, {i, j}, {j, i}, {j, j}};
    for (int q = 0; q < 4; q++) {
        nodes[2 * q] = pairs[q][0];
        nodes[2 * q + 1] = pairs[q][1];
        double sign = pairs[q][0] == pairs[q][1] ? 1.0 : -1.0;
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                K[9 * q + 3 * r + c] = sign * a * n[r] * n[c] - (pairs[q][0] == pairs[q][1]) * s * (r == c);
    }
}

static void test_edge_contact_and_separate_components(void **state)
{
    (void)state;
    double n[3] = {0.0, 0.6, 0.8};
    const double a = 4e8, s = 1e7;
    int nodes[16];
    double K[72];
    edge_blocks(0, 1, n, a, s, nodes, K);
    edge_blocks(2, 3, n, 2.0 * a, s, nodes + 8, K + 36);
    fem_psd p = {0};
    nc_error err;
    assert_int_equal(fem_psd_project(&p, 8, nodes, K, NULL, &err), 0);
    /* each edge: eigenvalues 2a − s (once, along (n, −n)) and −s (five times): 10 clipped */
    assert_int_equal(p.last_clipped, 10);
    for (size_t k = 0; k < p.n_blocks; k++)
        assert_true((p.nodes[2 * k] < 2) == (p.nodes[2 * k + 1] < 2));   /* no cross blocks */
    double A[3 * NMAX][3 * NMAX], E[3 * NMAX][3 * NMAX];
    assemble(p.n_blocks, p.nodes, p.K, A);
    double W[72];
    int wn[16];
    edge_blocks(0, 1, n, (2.0 * a - s) / 2.0, 0.0, wn, W);
    edge_blocks(2, 3, n, (4.0 * a - s) / 2.0, 0.0, wn + 8, W + 36);
    assemble(8, wn, W, E);
    assert_dense_near(A, E, 1e-12 * 4.0 * a);
    fem_psd_free(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rock_on_a_node),
        cmocka_unit_test(test_semidefinite_symmetric_part_is_kept),
        cmocka_unit_test(test_edge_contact_and_separate_components),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
