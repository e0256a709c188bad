/* cpl_compliance_line — points on the structure's linear answer (cpl_compliance_line.h). */
#include "cpl_compliance_line.h"

#include <stdlib.h>

#include "nc_lapack.h"

void cpl_compliance_answer(const cpl_compliance *c, const double *dF, double *du)
{
    const size_t k3 = 3 * c->n_nodes;
    for (size_t i = 0; i < c->n3; i++) {
        const double *row = c->S_interface + i * k3;
        double sum = 0.0;
        for (size_t q = 0; q < k3; q++) sum += row[q] * dF[q];
        du[i] = sum;
    }
}

int cpl_compliance_force_for(const cpl_compliance *c, const double *du_nodes, double *dF,
                             nc_error *err)
{
    const size_t k3 = 3 * c->n_nodes;
    if (k3 == 0) return 0;
    double *A = malloc(k3 * k3 * sizeof *A);
    int *ipiv = malloc(k3 * sizeof *ipiv);
    if (!A || !ipiv) {
        free(A);
        free(ipiv);
        return nc_error_set(err, 1, "out of memory for the compliance of %zu nodes", c->n_nodes);
    }
    /* column-major A: S with a supported dof's row and column replaced by the identity's */
    for (size_t a = 0; a < k3; a++) {
        const int fixed_a = c->S[a * k3 + a] == 0.0;
        dF[a] = fixed_a ? 0.0 : du_nodes[a];
        for (size_t b = 0; b < k3; b++) {
            const int fixed_b = c->S[b * k3 + b] == 0.0;
            A[b * k3 + a] = fixed_a || fixed_b ? (a == b ? 1.0 : 0.0) : c->S[a * k3 + b];
        }
    }
    const int n = (int)k3, one = 1;
    int info = 0;
    dgesv_(&n, &one, A, &n, ipiv, dF, &n, &info);
    free(A);
    free(ipiv);
    if (info != 0)
        return nc_error_set(err, 1, "the structure's compliance at %zu nodes is singular "
                            "(LAPACK info %d)", c->n_nodes, info);
    return 0;
}
