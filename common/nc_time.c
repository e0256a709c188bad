/* nc_time — time step and step count checks (see nc_time.h). */
#include "nc_time.h"

#include <math.h>

int nc_time_check_step(double dt_s, double t_max_s, const char *what, nc_error *err)
{
    if (!(dt_s > 0.0) || !isfinite(dt_s))
        return nc_error_set(err, 1, "%s: time step must be a finite number > 0, got %g s", what,
                            dt_s);
    double t = fabs(t_max_s);
    if (!isfinite(t)) return nc_error_set(err, 1, "%s: time %g s is not finite", what, t_max_s);
    double spacing = nextafter(t, INFINITY) - t;
    if (dt_s < NC_TIME_MIN_SPACINGS * spacing)
        return nc_error_set(err, 1, "%s: time step %g s is too small for times up to %g s "
                                    "(it must be at least %g float spacings of the time, %g s)",
                            what, dt_s, t, NC_TIME_MIN_SPACINGS, NC_TIME_MIN_SPACINGS * spacing);
    return 0;
}

int nc_time_step_count(double span_s, double dt_s, double max_steps, const char *what,
                       long *steps, nc_error *err)
{
    *steps = 0;
    if (!(dt_s > 0.0) || !isfinite(dt_s) || !isfinite(span_s))
        return nc_error_set(err, 1, "%s: time step %g s over %g s is not a usable step count",
                            what, dt_s, span_s);
    double count = ceil(span_s / dt_s - 1e-9);
    if (count < 0.0) count = 0.0;
    if (!(count <= max_steps))
        return nc_error_set(err, 1, "%s: %g s in steps of %g s would take %.3g steps (at most "
                                    "%.3g are allowed)", what, span_s, dt_s, count, max_steps);
    *steps = (long)count;
    return 0;
}
