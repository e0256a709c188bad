/* Unit tests of cpl_compliance_line: points on the structure's linear answer at the interface.
 *
 * The structure is a linear chain of three nodes (9 dofs) with springs between them and to
 * the ground and a mass term, as a dynamic step's matrix A (SPD); its answer to an interface
 * force F is u(F) = u₀ + A⁻¹ F. The compliance the FEM would send for the nodes N = {2, 0}
 * (in that order) is S = A⁻¹ on N's dofs and S_interface = A⁻¹'s rows of every dof on N's
 * columns. Checked against u(F) itself:
 *  - cpl_compliance_force_for: the force change dF that puts N at a target lands u(F₀ + dF)
 *    on the target (1e-10 relative);
 *  - cpl_compliance_answer: S_interface dF is u(F₀ + dF) − u(F₀) at every dof, N's and the
 *    free node's;
 *  - a supported dof (its row and column of S zero, as the FEM sends them) gets no force
 *    and the others still land on the target. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <string.h>

#include "../../coupler/cpl_compliance_line.h"
#include "nc_lapack.h"

#define NDOF 9

/* A: springs k_ground from each node to the ground, k_link between neighbours, in each
 * direction, with a direction-dependent factor so that directions differ, plus the mass
 * term m/(β Δt²) on the diagonal; Ainv its inverse (row-major, symmetric). */
static void chain(double *Ainv)
{
    const double k_ground = 2.0e5, k_link = 5.0e5, mass_term = 3.0e4;
    double A[NDOF * NDOF] = {0};
    for (int node = 0; node < 3; node++)
        for (int d = 0; d < 3; d++) {
            const int i = 3 * node + d;
            const double f = 1.0 + 0.5 * d;
            A[i * NDOF + i] += mass_term + k_ground * f;
            if (node < 2) {
                const int j = i + 3;
                A[i * NDOF + i] += k_link * f;
                A[j * NDOF + j] += k_link * f;
                A[i * NDOF + j] -= k_link * f;
                A[j * NDOF + i] -= k_link * f;
            }
        }
    /* a coupling between directions of node 1, so that S is not diagonal per node */
    A[3 * NDOF + 4] += 1.0e5;
    A[4 * NDOF + 3] += 1.0e5;
    double I[NDOF * NDOF] = {0};
    for (int i = 0; i < NDOF; i++) I[i * NDOF + i] = 1.0;
    int n = NDOF, ipiv[NDOF], info = 0;
    dgesv_(&n, &n, A, &n, ipiv, I, &n, &info);   /* symmetric: column-major is row-major */
    assert_int_equal(info, 0);
    memcpy(Ainv, I, sizeof I);
}

static const int32_t NODES[2] = {2, 0};

static int dof_of(int q) { return 3 * NODES[q / 3] + q % 3; }

/* The compliance of NODES from Ainv; supported: a dof of N (index in 0..5) held, or -1. */
static void compliance_of(const double *Ainv, int supported, double *S, double *rows,
                          cpl_compliance *c)
{
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++)
            S[a * 6 + b] = a == supported || b == supported ? 0.0
                                                            : Ainv[dof_of(a) * NDOF + dof_of(b)];
    for (int i = 0; i < NDOF; i++)
        for (int b = 0; b < 6; b++)
            rows[i * 6 + b] = b == supported ? 0.0 : Ainv[i * NDOF + dof_of(b)];
    memset(c, 0, sizeof *c);
    c->n_nodes = 2;
    c->nodes = (int32_t *)NODES;
    c->S = S;
    c->n3 = NDOF;
    c->S_interface = rows;
    c->has_interface = 1;
    c->valid = 1;
}

static void answer_of(const double *Ainv, const double *F, double *u)
{
    for (int i = 0; i < NDOF; i++) {
        u[i] = 0.01 * (i + 1);   /* u₀: the structure's motion without force */
        for (int j = 0; j < NDOF; j++) u[i] += Ainv[i * NDOF + j] * F[j];
    }
}

static void test_lands_on_target(void **state)
{
    (void)state;
    double Ainv[NDOF * NDOF], S[36], rows[NDOF * 6];
    cpl_compliance c;
    chain(Ainv);
    compliance_of(Ainv, -1, S, rows, &c);
    double F0[NDOF] = {0}, u0[NDOF], u1[NDOF], F1[NDOF], target[6], du[6], dF[6], move[NDOF];
    F0[2] = -1200.0;   /* the last step's force, on node 0 */
    F0[8] = -800.0;    /* and node 2 */
    answer_of(Ainv, F0, u0);
    for (int q = 0; q < 6; q++) {
        target[q] = u0[dof_of(q)] + 1e-3 * (q % 2 ? 1.0 : -2.0);
        du[q] = target[q] - u0[dof_of(q)];
    }
    nc_error err;
    assert_int_equal(cpl_compliance_force_for(&c, du, dF, &err), 0);
    memcpy(F1, F0, sizeof F1);
    for (int q = 0; q < 6; q++) F1[dof_of(q)] += dF[q];
    answer_of(Ainv, F1, u1);
    double worst = 0.0;
    for (int q = 0; q < 6; q++) worst = fmax(worst, fabs(u1[dof_of(q)] - target[q]));
    print_message("force_for: %.3g m from the target (moves of 1-2 mm)\n", worst);
    assert_below(worst, 1e-10 * 2e-3);
    /* the linear answer at every dof, node 1 (not in N) included */
    cpl_compliance_answer(&c, dF, move);
    worst = 0.0;
    for (int i = 0; i < NDOF; i++) worst = fmax(worst, fabs(u0[i] + move[i] - u1[i]));
    assert_below(worst, 1e-12);
    assert_true(fabs(move[3]) > 1e-5);   /* the free node does move */
}

static void test_supported_dof(void **state)
{
    (void)state;
    double Ainv[NDOF * NDOF], S[36], rows[NDOF * 6];
    cpl_compliance c;
    chain(Ainv);
    const int held = 4;   /* node 0, direction y */
    compliance_of(Ainv, held, S, rows, &c);
    double du[6] = {1e-3, -2e-3, 5e-4, 1e-3, 7e-4, -1e-3}, dF[6];
    nc_error err;
    assert_int_equal(cpl_compliance_force_for(&c, du, dF, &err), 0);
    assert_true(dF[held] == 0.0);
    for (int a = 0; a < 6; a++) {
        if (a == held) continue;
        double sum = 0.0;
        for (int b = 0; b < 6; b++) sum += S[a * 6 + b] * dF[b];
        assert_below(fabs(sum - du[a]), 1e-12);
    }
}

static void test_singular(void **state)
{
    (void)state;
    /* two identical columns on dofs that are not supported: no force puts them apart */
    double S[36] = {0}, rows[NDOF * 6] = {0}, du[6] = {1e-3, 0, 0, 0, 0, 0}, dF[6];
    for (int a = 0; a < 6; a++) S[a * 6 + a] = 1e-6;
    S[0 * 6 + 1] = S[1 * 6 + 0] = 1e-6;
    cpl_compliance c = {.n_nodes = 2, .nodes = (int32_t *)NODES, .S = S, .n3 = NDOF,
                        .S_interface = rows, .has_interface = 1, .valid = 1};
    nc_error err;
    assert_int_equal(cpl_compliance_force_for(&c, du, dF, &err), -1);
    assert_non_null(strstr(err.message, "singular"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lands_on_target),
        cmocka_unit_test(test_supported_dof),
        cmocka_unit_test(test_singular),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
