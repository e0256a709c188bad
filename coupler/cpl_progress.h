/* cpl_progress — what the user sees while the coupler runs.
 *
 * On a terminal: one status line rewritten in place (simulated time, step, iterations of the
 * last step, residual, Δt when the step control reduced it, elapsed and estimated remaining
 * wall time), at most 10 times a second. Otherwise (log file, pipe): a plain line every
 * `interval_s` seconds. Warnings (unconverged steps, rejected tries) and messages go on
 * their own lines. `quiet` prints only warnings and errors. Writes to the FILE the program
 * hands in; never exits.
 */
#ifndef CPL_PROGRESS_H
#define CPL_PROGRESS_H

#include <stdio.h>
#include "cpl_loop.h"

typedef struct cpl_progress {
    FILE *out;
    int tty, quiet;
    double interval_s;
    double wall_start, last_print;
    double sim_start, sim_end;
    double dt_nominal_s;        /* the status line shows Δt when a step is shorter */
    int line_open;              /* a status line is on screen without newline */
    long warnings;              /* unconverged steps reported */
    long energy_warnings;       /* steps above the energy guard's limit (the first is reported) */
    long rejections;            /* rejected tries reported */
    cpl_step_record last;
    int have_last;
} cpl_progress;

void cpl_progress_init(cpl_progress *p, FILE *out, int tty, int quiet, double interval_s,
                       double sim_start, double sim_end, double dt_nominal_s);
void cpl_progress_step(cpl_progress *p, const cpl_step_record *rec, int strong);
/* A rejected try: a warning line (every one up to 20, then every 100th). */
void cpl_progress_reject(cpl_progress *p, const cpl_reject_record *rec);
/* A message on its own line (clears the status line first). */
void cpl_progress_message(cpl_progress *p, const char *format, ...)
    __attribute__((format(printf, 2, 3)));
/* Final status line (always printed unless quiet) and newline. */
void cpl_progress_finish(cpl_progress *p);

#endif
