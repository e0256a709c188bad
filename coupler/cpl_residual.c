/* cpl_residual — interface residuals, scaled norms and the convergence test,
 * eqs. (27)–(30). */
#include "cpl_residual.h"

#include <math.h>

double cpl_scaled_norm(const double *x, size_t n)
{
    if (n == 0) return 0.0;
    /* scaled summation: no overflow for huge non-physical forces of a diverging iteration */
    double scale = 0.0, ssq = 1.0;
    for (size_t i = 0; i < n; i++) {
        double a = fabs(x[i]);
        if (a == 0.0) continue;
        if (scale < a) {
            ssq = 1.0 + ssq * (scale / a) * (scale / a);
            scale = a;
        } else {
            ssq += (a / scale) * (a / scale);
        }
    }
    return scale * sqrt(ssq) / sqrt((double)n);   /* eq. (27): ‖r‖ / sqrt(n_eq) */
}

double cpl_residual(const double *produced, const double *used, double *r, size_t n)
{
    for (size_t i = 0; i < n; i++) r[i] = produced[i] - used[i];   /* eqs. (28)–(30) */
    return cpl_scaled_norm(r, n);
}

int cpl_converged(double residual, double value_norm, double tol_abs, double tol_rel)
{
    if (!isfinite(residual)) return 0;
    if (residual < tol_abs) return 1;                               /* eq. (27) */
    return tol_rel > 0.0 && residual < tol_rel * value_norm;
}
