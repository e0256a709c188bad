/* cpl_history — the coupling history a run leaves in its output folder:
 *   DIR/coupling.h5   /steps/{time, dt, iterations, residual, converged, contact_force (×3),
 *                     in_contact, near_interface, min_gap}
 *                     /iterations/{step, iteration, residual, alpha, contact_force (×3),
 *                     fem_solved}
 *                     root attributes: scheme, relaxation, relaxed_quantity, tolerance, dt
 *   DIR/iterations.log  one row per step: "step time iterations converged residual"
 * Both are flushed after every step, so they stay readable if the coupler is killed.
 */
#ifndef CPL_HISTORY_H
#define CPL_HISTORY_H

#include <stdio.h>
#include "cpl_loop.h"
#include "nc_h5.h"

typedef struct cpl_history {
    nc_h5_file h5;
    nc_h5_series s_time, s_dt, s_iterations, s_residual, s_converged, s_force, s_contact,
        s_near, s_gap;
    nc_h5_series i_step, i_iteration, i_residual, i_alpha, i_force, i_fem_solved;
    int write_iterations;
    FILE *log;
    int open;
} cpl_history;

/* Creates both files in `dir` (which must exist). */
int cpl_history_open(cpl_history *h, const char *dir, const cpl_loop_settings *s,
                     int write_iterations, nc_error *err);
int cpl_history_iteration(cpl_history *h, const cpl_iteration_record *rec, nc_error *err);
int cpl_history_step(cpl_history *h, const cpl_step_record *rec, nc_error *err);
/* Stores the timing split as attributes of /timing, flushes and closes (safe to repeat). */
void cpl_history_close(cpl_history *h, const cpl_timing *timing);

#endif
