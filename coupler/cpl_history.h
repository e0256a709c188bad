/* cpl_history — the coupling history a run leaves in its output folder:
 *   DIR/coupling.h5   /steps/{time, dt, iterations, residual, converged, contact_force (×3),
 *                     in_contact, near_interface, min_gap, rejected}
 *                     /iterations/{step, iteration, residual, alpha, contact_force (×3),
 *                     fem_solved, attempt, dt, jacobian_miss (NAN where not checked),
 *                     compliance (1: the DEM solved against the structure's compliance)}
 *                     /rejections/{step, attempt, time, dt, next_dt, iterations, residual,
 *                     reason}
 *                     /energy/{fem_kinetic, fem_elastic, fem_potential, dem_kinetic,
 *                     dem_elastic, dem_potential (end of step), fem_interface_work,
 *                     dem_interface_work, interface_created, fem_dissipated, dem_dissipated,
 *                     external_work (of the step), created, input, limit, closure
 *                     (accumulated; cpl_energy.h), above}: one row per step, units "J"
 *                     (above: 1 when created > limit), NAN when unavailable
 *                     root attributes: scheme, relaxation, relaxed_quantity, tolerance, dt,
 *                     dt_min, grow_after; at the end the run's status (cpl_history_close)
 *   DIR/iterations.log  one row per step: "step time iterations converged residual dt
 *                     rejected created_J input_J", a "# rejected ..." comment line per
 *                     rejected try and one "# energy created ..." line at the first step
 *                     above the energy guard's limit
 * iterations.log is flushed after every step; coupling.h5 keeps its rows in memory and is
 * written when a row is added NC_H5_FLUSH_INTERVAL_S (nc_h5.h) or more of wall time after its
 * last write, at a checkpoint, by cpl_history_flush and when closed, so it stays readable if
 * the coupler is killed (as its last write left it).
 */
#ifndef CPL_HISTORY_H
#define CPL_HISTORY_H

#include <stdio.h>
#include "cpl_loop.h"
#include "nc_h5.h"

#define CPL_HISTORY_ENERGY_SERIES 17

typedef struct cpl_history {
    nc_h5_file h5;
    nc_h5_series s_time, s_dt, s_iterations, s_residual, s_converged, s_force, s_contact,
        s_near, s_gap, s_rejected;
    nc_h5_series i_step, i_iteration, i_residual, i_alpha, i_force, i_fem_solved, i_attempt,
        i_dt, i_jacobian_miss, i_compliance;
    nc_h5_series e_series[CPL_HISTORY_ENERGY_SERIES], e_above;
    nc_h5_series r_step, r_attempt, r_time, r_dt, r_next_dt, r_iterations, r_residual,
        r_reason;
    int write_iterations;
    long energy_warned;         /* energy-created lines written to the log */
    FILE *log;
    int open;
    /* what the files held at the last checkpoint (cpl_history_mark), restored by
     * cpl_history_resume */
    long mark_steps, mark_iterations, mark_rejections, mark_log_bytes;
    /* resuming: series are opened and cut back to the marks instead of created */
    int resuming;
    hsize_t keep;
} cpl_history;

/* Creates both files in `dir` (which must exist). */
int cpl_history_open(cpl_history *h, const char *dir, const cpl_loop_settings *s,
                     int write_iterations, nc_error *err);
/* Checkpoint: writes coupling.h5 and records the rows of each group and the length of the
 * log in the marks (call it after the step's row is appended), and adds the marks and energy_warned to a
 * checkpoint table (the same entries are loaded into a fresh, zeroed cpl_history). */
int cpl_history_mark(cpl_history *h, nc_error *err);
/* Writes the rows kept in memory to coupling.h5 now (a full disk is reported here). */
int cpl_history_flush(cpl_history *h, nc_error *err);
void cpl_history_checkpoint_entries(cpl_history *h, cpl_ckpt_table *t);
/* Resume: reopens both files of `dir` as they were at the checkpoint whose marks h holds
 * (loaded with cpl_history_checkpoint_entries): every series cut back to its rows, the log
 * truncated to its length; later rows are appended. */
int cpl_history_resume(cpl_history *h, const char *dir, const cpl_loop_settings *s,
                       int write_iterations, nc_error *err);
int cpl_history_iteration(cpl_history *h, const cpl_iteration_record *rec, nc_error *err);
int cpl_history_step(cpl_history *h, const cpl_step_record *rec, nc_error *err);
int cpl_history_reject(cpl_history *h, const cpl_reject_record *rec, nc_error *err);

/* How trustworthy a finished run is; written as root attributes by cpl_history_close. */
typedef struct cpl_run_status {
    int finished;               /* the run reached its end (no error, not interrupted) */
    int reliable;               /* finished, no unconverged step accepted, no guard fired */
    int accept_unconverged;     /* the user opted in to accepting unconverged steps */
    int energy_growth;          /* the energy guard fired (cpl_energy.h) */
    int accept_energy_growth;   /* the user opted in to accepting that */
    int impulse_loss;           /* the impulse guard fired (cpl_impulse.h) */
    int accept_impulse_loss;    /* the user opted in to accepting that */
    double impulse_missed_share;   /* |Σ missed| / Σ |given| (NAN: no interface Jacobian) */
} cpl_run_status;

/* Stores the timing split as attributes of /timing/total and the run's counts and status
 * (unconverged_steps, rejected_attempts, reduced_steps, min_dt_used, finished, reliable,
 * accept_unconverged, energy_growth, accept_energy_growth, energy_created, energy_input,
 * energy_first_step, energy_first_time, impulse_loss, accept_impulse_loss,
 * impulse_missed_share) as root attributes (status may be NULL: counts only), flushes and
 * closes (safe to repeat). */
void cpl_history_close(cpl_history *h, const cpl_timing *timing, const cpl_energy *energy,
                       const cpl_run_status *status);

#endif
