/* fem_gmres — GMRES with right preconditioning, for a Newton step whose tangent is not
 * symmetric.
 *
 * Why: the DEM's contact linearisation K = −dF/du is not symmetric (the closest point slides
 * along an edge with the motion, friction ties the tangential force to the normal motion,
 * the rock's lever couples nodes unevenly), while the FEM's matrix and its factorisations
 * (CHOLMOD LDLᵀ, the kept factor of modified Newton) are symmetric. Solving with only the
 * symmetric part leaves the interface iteration to correct the skew part, one coupling
 * iteration at a time (the outer iteration then converges linearly, docs/notes/
 * interface_jacobian.md "The skew part"). With the symmetric factor as preconditioner M, the
 * preconditioned operator A M⁻¹ = I + W M⁻¹ differs from the identity by the skew part W of
 * the few contact dofs, so GMRES reaches the exact Newton step in a handful of iterations
 * (at most rank(W) + 1), each one product with A and one solve with the factor. The same
 * holds for the sliding ropes' rank-one terms k g gᵀ, which the solver keeps out of the
 * factorised matrix (a dense block over each rope would fill the factor): W then also holds
 * them, one iteration each.
 *
 * Contract: solves A x = b for x (x starts from 0), with A and M⁻¹ given as callbacks on
 * vectors of length n. Converged when ‖b − A x‖ ≤ tol ‖b‖ (the Arnoldi residual, which equals
 * the true one up to rounding). Returns 0 converged, 1 not converged within max_iterations
 * (x then holds the last iterate, the least-squares best in the Krylov space), −1 when a
 * callback failed (err set by it). *iterations receives the iterations done. Work space is
 * allocated once by fem_gmres_reserve() and reused; no restarts. */
#ifndef FEM_GMRES_H
#define FEM_GMRES_H

#include "nc_error.h"

typedef int (*fem_gmres_apply)(void *ctx, const double *x, double *y, nc_error *err);

typedef struct fem_gmres {
    int n, max_iterations;
    double *V;        /* [(max_iterations + 1) n] Krylov basis */
    double *H;        /* [(max_iterations + 1) max_iterations] Hessenberg matrix, column-major */
    double *cs, *sn;  /* [max_iterations] Givens rotations */
    double *g;        /* [max_iterations + 1] rotated right-hand side */
    double *y, *z;    /* [max_iterations] coefficients; [n] work vector */
} fem_gmres;

/* Work space for systems of size n and up to max_iterations iterations; 0 or -1 (memory). */
int fem_gmres_reserve(fem_gmres *g, int n, int max_iterations, nc_error *err);
void fem_gmres_free(fem_gmres *g);
int fem_gmres_solve(fem_gmres *g, fem_gmres_apply apply_A, fem_gmres_apply apply_Minv, void *ctx,
                    const double *b, double *x, double tol, int max_iterations, int *iterations,
                    nc_error *err);

#endif
