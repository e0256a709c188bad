/* cpl_progress — what the user sees while the coupler runs.
 *
 * On a terminal: one status line rewritten in place, at most 10 times a second. Otherwise
 * (log file, pipe): a plain line every `interval_s` seconds. Most important first (a
 * terminal line is cut to the width):
 *   t = 0.31 s (20.7%), 00:40 left | contact 3 | rock 12.3 m/s, 87.5 kJ |
 *   deflection 0.312 m (max 0.48 m) | step 155, 4 it., res 1.20e-09, elapsed 00:12
 * simulated time, percent done, remaining wall time; contact with the net (number of
 * contacts when the DEM counts them), the rock's largest speed (when the DEM reports it) and
 * its kinetic energy, the net's largest deflection now and over the run; step, iterations of
 * the last step, residual, Δt when the step control reduced it, elapsed wall time.
 * The remaining time is the remaining simulated time at the rate of the last
 * CPL_PROGRESS_WINDOW_S seconds of wall time (a run slows down many times over once the rock
 * hits the net; a rate since the start would be far off). Warnings (unconverged steps,
 * rejected tries) and messages go on their own lines. `quiet` prints only warnings and
 * errors. Writes to the FILE the program hands in; never exits. The clock is replaceable
 * (tests).
 */
#ifndef CPL_PROGRESS_H
#define CPL_PROGRESS_H

#include <stddef.h>
#include <stdio.h>
#include "cpl_loop.h"

#define CPL_PROGRESS_WINDOW_S 30.0   /* the rate of this much recent wall time gives the ETA */
#define CPL_PROGRESS_SAMPLES 64      /* (wall, simulated) time samples kept over the window */

/* The engineering quantities of the last accepted step; NAN where unknown. */
typedef struct cpl_progress_watch {
    double contacts;            /* particle–net contacts (DEM value `contacts`) */
    double max_speed_m_s;       /* largest particle speed (DEM value `max_particle_speed_m_s`) */
    double kinetic_energy_j;    /* the DEM's kinetic energy (DEM value `kinetic_energy_j`) */
    double deflection_m;        /* largest |u| of the interface nodes */
} cpl_progress_watch;

typedef struct cpl_progress_sample {
    double wall_s, sim_s;
} cpl_progress_sample;

typedef struct cpl_progress {
    FILE *out;
    int tty, quiet;
    size_t width;               /* terminal columns the status line is cut to (0: no limit) */
    double interval_s;
    double (*now_s)(void *ctx); /* the wall clock (nc_clock_now_s unless replaced) */
    void *clock_ctx;
    double wall_start, last_print;
    double sim_start, sim_end;
    double dt_nominal_s;        /* the status line shows Δt when a step is shorter */
    int line_open;              /* a status line is on screen without newline */
    long warnings;              /* unconverged steps reported */
    long energy_warnings;       /* steps above the energy guard's limit (the first is reported) */
    long jacobian_warnings;     /* steps with particles left out of the DEM's linearisation
                                   (the first is reported) */
    long rejections;            /* rejected tries reported */
    cpl_step_record last;
    int have_last;
    cpl_progress_watch watch;
    double max_deflection_m;    /* largest deflection of the run so far */
    cpl_progress_sample samples[CPL_PROGRESS_SAMPLES];   /* ring, oldest at `first` */
    int first, count;
} cpl_progress;

void cpl_progress_init(cpl_progress *p, FILE *out, int tty, int quiet, double interval_s,
                       double sim_start, double sim_end, double dt_nominal_s);
/* Replaces the wall clock (and restarts the elapsed time and the rate window with it). */
void cpl_progress_use_clock(cpl_progress *p, double (*now_s)(void *ctx), void *ctx);
/* The engineering quantities of the step about to be reported (cpl_progress_step). */
void cpl_progress_set_watch(cpl_progress *p, const cpl_progress_watch *watch);
void cpl_progress_step(cpl_progress *p, const cpl_step_record *rec, int strong);
/* A rejected try: a warning line (every one up to 20, then every 100th). */
void cpl_progress_reject(cpl_progress *p, const cpl_reject_record *rec);
/* A message on its own line (clears the status line first). */
void cpl_progress_message(cpl_progress *p, const char *format, ...)
    __attribute__((format(printf, 2, 3)));
/* Final status line (always printed unless quiet) and newline. */
void cpl_progress_finish(cpl_progress *p);

/* The status line of the last step ("" before the first), not cut to the width. */
void cpl_progress_status(const cpl_progress *p, char *buf, size_t size);
/* Estimated remaining wall time (s) at the recent rate; NAN while unknown. */
double cpl_progress_remaining_s(const cpl_progress *p);

#endif
