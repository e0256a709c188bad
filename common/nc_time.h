/* nc_time — sanity of a time step against the times it is added to, and of step counts.
 *
 * The rule: a step dt is usable only if it is at least NC_TIME_MIN_SPACINGS (1e6) float
 * spacings of the largest |t| it is added to, so that t + dt moves t by about a million units
 * in the last place (each step's time is then rounded by at most 1e-6 of dt, and a loop
 * `t += dt` always advances). Below that, a run at t = 1e17 with dt = 1 would never move.
 * Step counts are checked before they are converted to integers, against a bound the caller
 * chooses (NC_TIME_MAX_STEPS for a whole run, NC_TIME_MAX_SUBSTEPS for one coupling step).
 */
#ifndef NC_TIME_H
#define NC_TIME_H

#include "nc_error.h"

#define NC_TIME_MIN_SPACINGS 1e6
#define NC_TIME_MAX_STEPS 1e9
#define NC_TIME_MAX_SUBSTEPS 1e8

/* Fails unless dt_s > 0, finite and dt_s >= NC_TIME_MIN_SPACINGS spacings of |t_max_s|.
 * `what` names the step in the message ("dem.json: dt_s"). */
int nc_time_check_step(double dt_s, double t_max_s, const char *what, nc_error *err);

/* *steps = ceil(span_s / dt_s) (with a 1e-9 tolerance for spans that are whole multiples);
 * fails when that exceeds max_steps, saying how many steps it would be. */
int nc_time_step_count(double span_s, double dt_s, double max_steps, const char *what,
                       long *steps, nc_error *err);

#endif
