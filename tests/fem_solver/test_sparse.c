/* test_sparse — the factorisation choice of fem_sparse (fem_sparse.h) on a matrix large
 * enough for CHOLMOD's "auto" to take a supernodal LL^T (a 24 x 24 grid of 3-dof nodes,
 * 1728 equations, the pattern of a square net):
 *  - positive definite: supernodal LL^T, solved to 1e-10 relative (residual of A x = b);
 *  - indefinite (negative diagonal on a few equations, as a contact linearisation's negative
 *    part): the factor turns into simplicial LDL^T for good, no UMFPACK LU, solved to 1e-10;
 *    later factorisations (positive definite again) stay LDL^T; the saved factor too;
 *  - "llt" on the same indefinite matrix falls back to LU and solves it. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../../fem_solver/fem_sparse.h"

#define GRID 24
#define NODES (GRID * GRID)
#define NEQ (3 * NODES)

typedef struct grid {
    fem_sparse K;
    int n_elem;
    int *elem_eq, *slot;
} grid;

/* Elements between grid neighbours, every dof free. */
static void build(grid *g, int mode)
{
    g->n_elem = 2 * GRID * (GRID - 1);
    g->elem_eq = malloc(6 * (size_t)g->n_elem * sizeof(int));
    g->slot = malloc(36 * (size_t)g->n_elem * sizeof(int));
    assert_non_null(g->elem_eq);
    assert_non_null(g->slot);
    int e = 0;
    for (int i = 0; i < GRID; i++)
        for (int j = 0; j < GRID; j++) {
            const int a = i * GRID + j;
            const int nb[2] = {j + 1 < GRID ? a + 1 : -1, i + 1 < GRID ? a + GRID : -1};
            for (int k = 0; k < 2; k++) {
                if (nb[k] < 0) continue;
                for (int c = 0; c < 3; c++) {
                    g->elem_eq[6 * e + c] = 3 * a + c;
                    g->elem_eq[6 * e + 3 + c] = 3 * nb[k] + c;
                }
                e++;
            }
        }
    assert_int_equal(e, g->n_elem);
    nc_error err;
    assert_int_equal(fem_sparse_build(&g->K, NEQ, g->n_elem, g->elem_eq, g->slot, mode, &err), 0);
}

/* Values: per element the bar-like block k [[I, -I], [-I, I]] (k varies), plus a diagonal
 * `diag` on every equation, minus `negative` on equations 100..105. */
static void fill(grid *g, double diag, double negative)
{
    memset(g->K.x, 0, (size_t)g->K.nnz * sizeof(double));
    for (int e = 0; e < g->n_elem; e++) {
        const double k = 1.0 + 0.3 * sin(0.7 * e);
        for (int a = 0; a < 6; a++)
            for (int b = 0; b < 6; b++) {
                const int slot = g->slot[36 * e + 6 * a + b];
                if (slot < 0 || a % 3 != b % 3) continue;
                g->K.x[slot] += (a / 3 == b / 3 ? k : -k);
            }
    }
    for (int q = 0; q < NEQ; q++) g->K.x[g->K.diag[q]] += diag - (q >= 100 && q < 106 ? negative : 0.0);
}

static void check_solve(grid *g)
{
    static double b[NEQ], x[NEQ], Ax[NEQ];
    nc_error err;
    for (int q = 0; q < NEQ; q++) b[q] = cos(0.37 * q) + 0.5;
    assert_int_equal(fem_sparse_solve(&g->K, b, x, &err), 0);
    fem_sparse_matvec(&g->K, x, Ax);
    double r2 = 0, b2 = 0;
    for (int q = 0; q < NEQ; q++) {
        r2 += (Ax[q] - b[q]) * (Ax[q] - b[q]);
        b2 += b[q] * b[q];
    }
    assert_below(sqrt(r2), 1e-10 * sqrt(b2));
}

static void release(grid *g)
{
    fem_sparse_free(&g->K);
    free(g->elem_eq);
    free(g->slot);
}

static void test_auto_turns_to_ldlt(void **state)
{
    (void)state;
    grid g;
    build(&g, 0);
    nc_error err;
    int bad = -1;
    fill(&g, 0.05, 0.0);
    assert_int_equal(fem_sparse_factorize(&g.K, &bad, &err), 0);
    /* the premise: CHOLMOD chose a supernodal LL^T for this size */
    assert_true(g.K.L->is_super);
    assert_int_equal(g.K.switched_to_ldlt, 0);
    check_solve(&g);
    assert_int_equal(fem_sparse_save_factor(&g.K, &err), 0);

    fill(&g, 0.05, 3.0);   /* indefinite: six negative diagonal entries */
    assert_int_equal(fem_sparse_factorize(&g.K, &bad, &err), 0);
    assert_int_equal(g.K.switched_to_ldlt, 1);
    assert_int_equal(g.K.use_lu, 0);
    assert_false(g.K.L->is_super);
    assert_false(g.K.L->is_ll);
    assert_int_equal(g.K.lu_count, 0);
    check_solve(&g);

    /* the saved factor was turned too: a restore brings back an LDL^T factor */
    assert_int_equal(fem_sparse_restore_factor(&g.K, &err), 0);
    assert_false(g.K.L->is_super);
    fill(&g, 0.05, 0.0);
    assert_int_equal(fem_sparse_factorize(&g.K, &bad, &err), 0);
    assert_false(g.K.L->is_super);
    check_solve(&g);
    release(&g);
}

static void test_llt_falls_back_to_lu(void **state)
{
    (void)state;
    grid g;
    build(&g, 2);
    nc_error err;
    int bad = -1;
    fill(&g, 0.05, 3.0);
    assert_int_equal(fem_sparse_factorize(&g.K, &bad, &err), 0);
    assert_int_equal(g.K.use_lu, 1);
    assert_int_equal(g.K.switched_to_ldlt, 0);
    check_solve(&g);
    release(&g);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_auto_turns_to_ldlt),
        cmocka_unit_test(test_llt_falls_back_to_lu),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
