/* cpl_impulse — the interface's momentum balance (cpl_impulse.h). */
#include "cpl_impulse.h"

#include <math.h>
#include <string.h>

void cpl_impulse_settings_default(cpl_impulse_settings *s)
{
    s->tol_rel = 0.05;
    s->tol_abs_ns = 1e-6;
}

void cpl_impulse_init(cpl_impulse *m, const cpl_impulse_settings *s)
{
    memset(m, 0, sizeof *m);
    m->s = *s;
    m->first_step = -1;
    m->first_time_s = NAN;
}

static double norm3(const double *x)
{
    return sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
}

double cpl_impulse_missed_share(const cpl_impulse *m)
{
    return m->given_abs_ns > 0.0 ? norm3(m->missed_ns) / m->given_abs_ns : 0.0;
}

static int above(const cpl_impulse *m)
{
    return m->given_abs_ns > m->s.tol_abs_ns && cpl_impulse_missed_share(m) > m->s.tol_rel;
}

int cpl_impulse_fired(const cpl_impulse *m)
{
    return above(m);
}

/* one step's resultants of force and correction (NULL: none) */
static void step_sums(const double *force, const double *correction, size_t n_nodes,
                      double given[3], double missed[3])
{
    for (int c = 0; c < 3; c++) given[c] = missed[c] = 0.0;
    for (size_t i = 0; i < n_nodes; i++)
        for (int c = 0; c < 3; c++) {
            given[c] += force[3 * i + c];
            if (correction) missed[c] += correction[3 * i + c];
        }
}

double cpl_impulse_share_after(const cpl_impulse *m, double dt_s, const double *force,
                               const double *correction, size_t n_nodes, double *own)
{
    double given[3], missed[3];
    step_sums(force, correction, n_nodes, given, missed);
    if (own) {
        const double g = norm3(given), c = norm3(missed);
        *own = c > 0.0 ? (g > 0.0 ? c / g : INFINITY) : 0.0;
    }
    const double scale = m->given_abs_ns + norm3(given) * dt_s;
    if (!(scale > 0.0)) return 0.0;
    for (int c = 0; c < 3; c++) missed[c] = m->missed_ns[c] + missed[c] * dt_s;
    return norm3(missed) / scale;
}

void cpl_impulse_step(cpl_impulse *m, long step, double end_time_s, double dt_s,
                      const double *force, const double *correction, size_t n_nodes)
{
    double given[3], missed[3];
    step_sums(force, correction, n_nodes, given, missed);
    for (int c = 0; c < 3; c++) {
        m->given_ns[c] += given[c] * dt_s;
        m->missed_ns[c] += missed[c] * dt_s;
    }
    m->given_abs_ns += norm3(given) * dt_s;
    if (m->first_step < 0 && above(m)) {
        m->first_step = step;
        m->first_time_s = end_time_s;
    }
}
