/* cpl_progress — live status line on a terminal, periodic plain lines otherwise. */
#include "cpl_progress.h"

#include <math.h>
#include <stdarg.h>
#include <string.h>

#include "nc_clock.h"

static double default_clock(void *ctx)
{
    (void)ctx;
    return nc_clock_now_s();
}

static double now(const cpl_progress *p)
{
    return p->now_s(p->clock_ctx);
}

static void restart(cpl_progress *p)
{
    p->wall_start = p->last_print = now(p);
    p->samples[0] = (cpl_progress_sample){p->wall_start, p->sim_start};
    p->first = 0;
    p->count = 1;
}

void cpl_progress_init(cpl_progress *p, FILE *out, int tty, int quiet, double interval_s,
                       double sim_start, double sim_end, double dt_nominal_s)
{
    memset(p, 0, sizeof *p);
    p->out = out;
    p->tty = tty;
    p->quiet = quiet;
    p->interval_s = interval_s;
    p->now_s = default_clock;
    p->sim_start = sim_start;
    p->sim_end = sim_end;
    p->dt_nominal_s = dt_nominal_s;
    p->watch = (cpl_progress_watch){NAN, NAN, NAN, NAN};
    restart(p);
}

void cpl_progress_use_clock(cpl_progress *p, double (*now_s)(void *ctx), void *ctx)
{
    p->now_s = now_s ? now_s : default_clock;
    p->clock_ctx = ctx;
    restart(p);
}

void cpl_progress_set_watch(cpl_progress *p, const cpl_progress_watch *watch)
{
    p->watch = *watch;
    if (isfinite(watch->deflection_m) && watch->deflection_m > p->max_deflection_m)
        p->max_deflection_m = watch->deflection_m;
}

static const cpl_progress_sample *sample(const cpl_progress *p, int k)
{
    return &p->samples[(p->first + k) % CPL_PROGRESS_SAMPLES];
}

/* One sample per window / samples of wall time: the ring spans the whole window. */
static void add_sample(cpl_progress *p, double wall_s, double sim_s)
{
    const double spacing = CPL_PROGRESS_WINDOW_S / CPL_PROGRESS_SAMPLES;
    if (p->count > 0 && wall_s - sample(p, p->count - 1)->wall_s < spacing) return;
    if (p->count == CPL_PROGRESS_SAMPLES) {
        p->first = (p->first + 1) % CPL_PROGRESS_SAMPLES;
        p->count--;
    }
    p->samples[(p->first + p->count) % CPL_PROGRESS_SAMPLES] =
        (cpl_progress_sample){wall_s, sim_s};
    p->count++;
}

double cpl_progress_remaining_s(const cpl_progress *p)
{
    if (!p->have_last) return NAN;
    double t = now(p), sim = p->last.time_s;
    if (sim >= p->sim_end) return 0.0;
    /* the newest sample at least a window old, else the oldest: the rate of the last
     * window (of the run so far while it is shorter) */
    int k = 0;
    while (k + 1 < p->count && sample(p, k + 1)->wall_s <= t - CPL_PROGRESS_WINDOW_S) k++;
    const cpl_progress_sample *s = sample(p, k);
    if (!(sim > s->sim_s) || !(t > s->wall_s)) return NAN;
    double rate = (sim - s->sim_s) / (t - s->wall_s);   /* simulated s per wall s */
    return (p->sim_end - sim) / rate;
}

static void clock_text(char *buf, size_t size, double s)
{
    if (!isfinite(s) || s < 0) {
        snprintf(buf, size, "--:--");
        return;
    }
    long t = (long)(s + 0.5);
    if (t >= 3600) snprintf(buf, size, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
    else snprintf(buf, size, "%02ld:%02ld", t / 60, t % 60);
}

static void energy_text(char *buf, size_t size, double j)
{
    double a = fabs(j);
    if (a >= 1e6) snprintf(buf, size, "%.3g MJ", j / 1e6);
    else if (a >= 1e3) snprintf(buf, size, "%.3g kJ", j / 1e3);
    else snprintf(buf, size, "%.3g J", j);
}

/* "contact 3 | rock 12.3 m/s, 87.5 kJ | deflection 0.312 m (max 0.48 m)" */
static void watch_text(const cpl_progress *p, char *buf, size_t size)
{
    const cpl_progress_watch *w = &p->watch;
    int on = p->last.in_contact || (isfinite(w->contacts) && w->contacts > 0);
    char contact[48], rock[96] = "", net[96] = "";
    if (!on) snprintf(contact, sizeof contact, "no contact");
    else if (isfinite(w->contacts) && w->contacts > 0)
        snprintf(contact, sizeof contact, "contact %.0f", w->contacts);
    else snprintf(contact, sizeof contact, "contact");
    char speed[32] = "", energy[32] = "";
    if (isfinite(w->max_speed_m_s)) snprintf(speed, sizeof speed, "%.3g m/s", w->max_speed_m_s);
    if (isfinite(w->kinetic_energy_j)) energy_text(energy, sizeof energy, w->kinetic_energy_j);
    if (speed[0] || energy[0])
        snprintf(rock, sizeof rock, " | rock %s%s%s", speed, speed[0] && energy[0] ? ", " : "",
                 energy);
    if (isfinite(w->deflection_m))
        snprintf(net, sizeof net, " | deflection %.3g m (max %.3g m)", w->deflection_m,
                 p->max_deflection_m);
    snprintf(buf, size, "%s%s%s", contact, rock, net);
}

void cpl_progress_status(const cpl_progress *p, char *buf, size_t size)
{
    if (!p->have_last) {
        if (size) buf[0] = '\0';
        return;
    }
    double elapsed = now(p) - p->wall_start;
    const cpl_step_record *r = &p->last;
    double done = (r->time_s - p->sim_start) / (p->sim_end - p->sim_start);
    char e[32], rem[32], dt[48] = "", watch[256];
    clock_text(e, sizeof e, elapsed);
    clock_text(rem, sizeof rem, cpl_progress_remaining_s(p));
    /* the last step of a run may be shorter only to end on the end time */
    if (r->dt_s < p->dt_nominal_s * (1.0 - 1e-9) && r->time_s < p->sim_end - 1e-9 * p->dt_nominal_s)
        snprintf(dt, sizeof dt, ", dt %.3g s (reduced)", r->dt_s);
    watch_text(p, watch, sizeof watch);
    snprintf(buf, size, "t = %.6g s (%.1f%%), %s left | %s | step %ld, %d it., res %.2e%s, "
             "elapsed %s", r->time_s, 100.0 * done, rem, watch, r->step, r->iterations,
             r->residual, dt, e);
}

static void clear_line(cpl_progress *p)
{
    if (p->line_open) {
        fputs("\r\033[K", p->out);
        p->line_open = 0;
    }
}

void cpl_progress_message(cpl_progress *p, const char *format, ...)
{
    clear_line(p);
    va_list args;
    va_start(args, format);
    vfprintf(p->out, format, args);
    va_end(args);
    fputc('\n', p->out);
    fflush(p->out);
}

void cpl_progress_step(cpl_progress *p, const cpl_step_record *rec, int strong)
{
    p->last = *rec;
    p->have_last = 1;
    double t = now(p);
    add_sample(p, t, rec->time_s);
    if (strong && !rec->converged) {
        p->warnings++;
        /* every unconverged step up to 20, then every 100th, so a bad run stays readable */
        if (p->warnings <= 20 || p->warnings % 100 == 0)
            cpl_progress_message(p, "warning: step %ld (t = %.6g s) not converged after %d "
                                 "iterations at dt = %.3g s, residual %.3e accepted (%ld such "
                                 "steps so far)", rec->step, rec->time_s, rec->iterations,
                                 rec->dt_s, rec->residual, p->warnings);
    }
    if (rec->energy.above && p->energy_warnings++ == 0)
        cpl_progress_message(p, "warning: step %ld (t = %.6g s): the run has created %.6g J of "
                             "energy, above the limit %.6g J (energy_tolerance x input energy "
                             "%.6g J + energy_tolerance_abs)", rec->step, rec->time_s,
                             rec->energy.created_j, rec->energy.limit_j, rec->energy.input_j);
    /* the first step only: the summary gives the count (coupler/README.md) */
    if (rec->jacobian_dropped > 0 && p->jacobian_warnings++ == 0)
        cpl_progress_message(p, "warning: step %ld (t = %.6g s): the DEM left %d particle(s) "
                             "out of the interface Jacobian (a particle touching more net "
                             "nodes than it linearises, dem_solver/README.md); their contact "
                             "reaches the FEM as a force only and the coupling converges "
                             "more slowly", rec->step, rec->time_s, rec->jacobian_dropped);
    if (p->quiet) return;
    double every = p->tty ? 0.1 : p->interval_s;
    if (t - p->last_print < every) return;
    p->last_print = t;
    char text[512];
    cpl_progress_status(p, text, sizeof text);
    if (p->tty) {
        /* a line longer than the terminal would wrap, and \r only returns to its last row */
        if (p->width > 1 && strlen(text) > p->width - 1) text[p->width - 1] = '\0';
        fprintf(p->out, "\r%s\033[K", text);
        p->line_open = 1;
    } else {
        fprintf(p->out, "%s\n", text);
    }
    fflush(p->out);
}

void cpl_progress_reject(cpl_progress *p, const cpl_reject_record *rec)
{
    p->rejections++;
    if (p->rejections > 20 && p->rejections % 100 != 0) return;
    cpl_progress_message(p, "warning: step %ld (t = %.6g s, dt = %.3g s) rejected: %s after %d "
                         "iterations (residual %.3e); retrying with dt = %.3g s (%ld rejected "
                         "tries so far)%s%s", rec->step, rec->time_s, rec->dt_s,
                         cpl_reject_reason_text(rec->reason), rec->iterations, rec->residual,
                         rec->next_dt_s, p->rejections, rec->message[0] ? ": " : "",
                         rec->message);
}

void cpl_progress_finish(cpl_progress *p)
{
    if (p->quiet || !p->have_last) {
        clear_line(p);
        return;
    }
    char text[512];
    cpl_progress_status(p, text, sizeof text);
    clear_line(p);
    fprintf(p->out, "%s\n", text);
    fflush(p->out);
}
