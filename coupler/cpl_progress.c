/* cpl_progress — live status line on a terminal, periodic plain lines otherwise. */
#include "cpl_progress.h"

#include <math.h>
#include <stdarg.h>
#include <string.h>

#include "nc_clock.h"

void cpl_progress_init(cpl_progress *p, FILE *out, int tty, int quiet, double interval_s,
                       double sim_start, double sim_end, double dt_nominal_s)
{
    memset(p, 0, sizeof *p);
    p->out = out;
    p->tty = tty;
    p->quiet = quiet;
    p->interval_s = interval_s;
    p->wall_start = p->last_print = nc_clock_now_s();
    p->sim_start = sim_start;
    p->sim_end = sim_end;
    p->dt_nominal_s = dt_nominal_s;
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

static void status_text(const cpl_progress *p, char *buf, size_t size)
{
    double elapsed = nc_clock_now_s() - p->wall_start;
    const cpl_step_record *r = &p->last;
    double done = (r->time_s - p->sim_start) / (p->sim_end - p->sim_start);
    double eta = done > 0 ? elapsed * (1.0 - done) / done : NAN;
    char e[32], rem[32], dt[48] = "";
    clock_text(e, sizeof e, elapsed);
    clock_text(rem, sizeof rem, eta);
    /* the last step of a run may be shorter only to end on the end time */
    if (r->dt_s < p->dt_nominal_s * (1.0 - 1e-9) && r->time_s < p->sim_end - 1e-9 * p->dt_nominal_s)
        snprintf(dt, sizeof dt, "  dt %.3g s (reduced)", r->dt_s);
    snprintf(buf, size, "t = %.6g s (%5.1f%%)  step %ld  iterations %d  residual %.2e%s  "
             "elapsed %s  remaining %s", r->time_s, 100.0 * done, r->step, r->iterations,
             r->residual, dt, e, rem);
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
    if (p->quiet) return;
    double now = nc_clock_now_s();
    double every = p->tty ? 0.1 : p->interval_s;
    if (now - p->last_print < every) return;
    p->last_print = now;
    char text[256];
    status_text(p, text, sizeof text);
    if (p->tty) {
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
    char text[256];
    status_text(p, text, sizeof text);
    clear_line(p);
    fprintf(p->out, "%s\n", text);
    fflush(p->out);
}
