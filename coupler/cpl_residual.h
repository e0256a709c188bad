/* cpl_residual — interface residuals, eqs. (28)–(30), their scaled norm and the convergence
 * test, eq. (27).
 *
 * A residual is r^k = x̃^k − x^k: the value a solver produced in iteration k minus the value
 * that was used as the input of iteration k (the relaxed value of iteration k − 1). Its
 * size is the scaled norm ‖r‖ / sqrt(n_eq), n_eq = number of interface dofs in the vector.
 */
#ifndef CPL_RESIDUAL_H
#define CPL_RESIDUAL_H

#include <stddef.h>

/* ‖x‖ / sqrt(n), 0 for n = 0. */
double cpl_scaled_norm(const double *x, size_t n);

/* r = produced − used, returns the scaled norm of r (eqs. (28), (29), (30)). */
double cpl_residual(const double *produced, const double *used, double *r, size_t n);

/* Convergence criterion of eq. (27) with an optional relative part:
 * converged when residual < tol_abs, or (tol_rel > 0 and residual < tol_rel · value_norm),
 * where residual and value_norm are scaled norms of r and of the produced value. */
int cpl_converged(double residual, double value_norm, double tol_abs, double tol_rel);

#endif
