/* cpl_jacobian_check — the DEM's linearisation against central differences of its step
 * (cpl_jacobian_check.h). */
#include "cpl_jacobian_check.h"

#include <math.h>

double cpl_jacobian_check_epsilon(const double *du, const double *dv, size_t n3, double dt_s)
{
    double largest = 0.0;
    for (size_t i = 0; i < n3; i++) {
        largest = fmax(largest, fabs(du[i]));
        largest = fmax(largest, dt_s * fabs(dv[i]));
    }
    if (!(largest > 0.0)) return 0.0;
    const double probe_m = fmin(fmax(CPL_JACOBIAN_CHECK_FRACTION * largest,
                                     CPL_JACOBIAN_CHECK_MIN_M), CPL_JACOBIAN_CHECK_MAX_M);
    return probe_m / largest;
}

double cpl_jacobian_check_miss(const double *f_plus, const double *f_minus, double eps,
                               const double *predicted, size_t n3)
{
    double miss = 0.0, diff = 0.0, pred = 0.0;
    for (size_t i = 0; i < n3; i++) {
        const double d = (f_plus[i] - f_minus[i]) / (2.0 * eps);
        miss += (d - predicted[i]) * (d - predicted[i]);
        diff += d * d;
        pred += predicted[i] * predicted[i];
    }
    const double scale = fmax(diff, pred);
    return scale > 0.0 ? sqrt(miss / scale) : NAN;
}

void cpl_jacobian_check_add(cpl_jacobian_check *c, double miss, long step, int iteration,
                            double time_s)
{
    if (isnan(miss)) return;
    c->checks++;
    if (miss > CPL_JACOBIAN_CHECK_WARN) c->missed++;
    if (miss > c->worst) {
        c->worst = miss;
        c->worst_step = step;
        c->worst_iteration = iteration;
        c->worst_time_s = time_s;
    }
}
