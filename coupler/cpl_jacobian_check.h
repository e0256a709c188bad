/* cpl_jacobian_check — an opt-in test of the DEM's interface linearisation against the DEM's
 * own step (coupler.json "jacobian_check").
 *
 * Interface-Jacobian coupling converges quadratically only while the DEM's K = −∂F/∂u and
 * C = −∂F/∂u̇ are the derivatives of the force it returns; a wrong term turns the iteration
 * linear at a rate of about its relative error, and no unit test of a participant written
 * elsewhere guarantees it. The check takes the linearisation an iteration's structure solve
 * used, about the DEM input x = (u, u̇) of that iteration, and the step d the iteration then
 * took to the next input, and solves the DEM's step twice more, at x ± ε d:
 *
 *   D = (F(x + ε d) − F(x − ε d)) / (2 ε)    (central difference along d)
 *   P = −(K d_u + C d_u̇)                     (the linearisation's prediction,
 *                                             cpl_jacobian_apply)
 *   miss = ‖D − P‖ / max(‖D‖, ‖P‖)
 *
 * ε makes the largest displacement component of ε d, or Δt times the largest velocity
 * component, a thousandth of that of d, but at least CPL_JACOBIAN_CHECK_MIN_M (rounding)
 * and at most CPL_JACOBIAN_CHECK_MAX_M: small against the step and against the distance to
 * where a contact begins or ends, which the iteration approaches (a probe across it shows
 * as a miss). A wrong derivative shows at every step size. */
#ifndef CPL_JACOBIAN_CHECK_H
#define CPL_JACOBIAN_CHECK_H

#include <stddef.h>

#define CPL_JACOBIAN_CHECK_FRACTION 1e-3
#define CPL_JACOBIAN_CHECK_MIN_M 1e-10
#define CPL_JACOBIAN_CHECK_MAX_M 1e-7
/* a relative miss above this slows Newton's iteration noticeably: it is counted and named */
#define CPL_JACOBIAN_CHECK_WARN 1e-3

/* What the checks of a run found. */
typedef struct cpl_jacobian_check {
    long checks;            /* linearisations checked */
    long missed;            /* ... with a relative miss above CPL_JACOBIAN_CHECK_WARN */
    long solves;            /* extra DEM solves the checks took (2 per check) */
    double worst;           /* the largest relative miss (0: none checked) */
    long worst_step;        /* where it was: step, iteration, start time of the step */
    int worst_iteration;
    double worst_time_s;
} cpl_jacobian_check;

/* ε for the step (du, dv) (n3 each) of a step of dt_s; 0 when the step is zero. */
double cpl_jacobian_check_epsilon(const double *du, const double *dv, size_t n3, double dt_s);

/* The relative miss of the prediction `predicted` against the central difference of
 * f_plus and f_minus at ±eps; NAN when both are zero (nothing to compare). */
double cpl_jacobian_check_miss(const double *f_plus, const double *f_minus, double eps,
                               const double *predicted, size_t n3);

/* Adds one check's miss (NAN: not counted) to the run's record. */
void cpl_jacobian_check_add(cpl_jacobian_check *c, double miss, long step, int iteration,
                            double time_s);

#endif
