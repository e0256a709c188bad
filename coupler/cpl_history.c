/* cpl_history — coupling.h5 and iterations.log, appended step by step (see the header for
 * when each reaches the disk). */
#include "cpl_history.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <unistd.h>

/* /energy/<name> datasets in the order of energy_values() */
static const char *const energy_names[CPL_HISTORY_ENERGY_SERIES] = {
    "fem_kinetic", "fem_elastic", "fem_potential", "dem_kinetic", "dem_elastic", "dem_potential",
    "fem_interface_work", "dem_interface_work", "interface_created", "fem_dissipated",
    "dem_dissipated", "external_work", "created", "input", "limit", "closure",
    "fem_numerical_dissipated"};

static void energy_values(const cpl_energy_record *e, double *v)
{
    const double all[CPL_HISTORY_ENERGY_SERIES] = {
        e->fem_kinetic_j, e->fem_elastic_j, e->fem_potential_j, e->dem_kinetic_j,
        e->dem_elastic_j, e->dem_potential_j, e->fem_interface_work_j, e->dem_interface_work_j,
        e->interface_created_j, e->fem_dissipated_j, e->dem_dissipated_j, e->external_work_j,
        e->created_j, e->input_j, e->limit_j, e->closure_j, e->fem_numerical_j};
    memcpy(v, all, sizeof all);
}

/* a new series, or (resuming) the existing one cut back to h->keep rows */
static int series(cpl_history *h, nc_h5_series *s, const char *path, nc_h5_type type, int cols,
                  const char *units, nc_error *err)
{
    hsize_t row[1] = {(hsize_t)cols};
    if (h->resuming)
        return nc_h5_series_open(&h->h5, s, path, type, cols > 1 ? 2 : 1, cols > 1 ? row : NULL,
                                 h->keep, err);
    return nc_h5_series_create_units(&h->h5, s, path, type, cols > 1 ? 2 : 1,
                                     cols > 1 ? row : NULL, units, err);
}

static int open_files(cpl_history *h, const char *dir, const cpl_loop_settings *s,
                      int write_iterations, nc_error *err);

int cpl_history_open(cpl_history *h, const char *dir, const cpl_loop_settings *s,
                     int write_iterations, nc_error *err)
{
    memset(h, 0, sizeof *h);
    return open_files(h, dir, s, write_iterations, err);
}

int cpl_history_resume(cpl_history *h, const char *dir, const cpl_loop_settings *s,
                       int write_iterations, nc_error *err)
{
    cpl_history marks = *h;
    memset(h, 0, sizeof *h);
    h->mark_steps = marks.mark_steps;
    h->mark_iterations = marks.mark_iterations;
    h->mark_rejections = marks.mark_rejections;
    h->mark_log_bytes = marks.mark_log_bytes;
    h->energy_warned = marks.energy_warned;
    h->resuming = 1;
    return open_files(h, dir, s, write_iterations, err);
}

/* coupling.h5 is written when a row comes NC_H5_FLUSH_INTERVAL_S of wall time after its last
 * write (its rows wait in memory in between, nc_h5_set_buffered) */
static int flush_due(cpl_history *h, nc_error *err)
{
    return nc_h5_flush_due(&h->h5, err) < 0 ? -1 : 0;
}

int cpl_history_flush(cpl_history *h, nc_error *err)
{
    if (!h->open) return 0;
    return nc_h5_flush(&h->h5, err);
}

int cpl_history_mark(cpl_history *h, nc_error *err)
{
    if (!h->open) return 0;
    /* the rows up to the checkpoint are in the file before the checkpoint names them */
    if (cpl_history_flush(h, err)) return -1;
    h->mark_steps = (long)nc_h5_series_rows(&h->s_time);
    h->mark_iterations = (long)nc_h5_series_rows(&h->i_step);
    h->mark_rejections = (long)nc_h5_series_rows(&h->r_step);
    h->mark_log_bytes = h->log ? ftell(h->log) : 0;
    return 0;
}

void cpl_history_checkpoint_entries(cpl_history *h, cpl_ckpt_table *t)
{
    cpl_ckpt_long(t, "history", "steps_rows", &h->mark_steps);
    cpl_ckpt_long(t, "history", "iterations_rows", &h->mark_iterations);
    cpl_ckpt_long(t, "history", "rejections_rows", &h->mark_rejections);
    cpl_ckpt_long(t, "history", "log_bytes", &h->mark_log_bytes);
    cpl_ckpt_long(t, "history", "energy_warned", &h->energy_warned);
}

static int open_files(cpl_history *h, const char *dir, const cpl_loop_settings *s,
                      int write_iterations, nc_error *err)
{
    char path[2048];
    snprintf(path, sizeof path, "%s/coupling.h5", dir);
    if (h->resuming ? nc_h5_open(&h->h5, path, err) : nc_h5_create(&h->h5, path, err)) return -1;
    nc_h5_set_buffered(&h->h5);
    h->open = 1;
    h->write_iterations = write_iterations;
    /* the residual is a scaled norm of the relaxed quantity */
    const char *res_units = s->relaxed == CPL_RELAXED_FORCE ? "N" : "m, m/s";
    h->keep = (hsize_t)h->mark_steps;
    if (series(h, &h->s_time, "/steps/time", NC_H5_F64, 1, "s", err) ||
        series(h, &h->s_dt, "/steps/dt", NC_H5_F64, 1, "s", err) ||
        series(h, &h->s_iterations, "/steps/iterations", NC_H5_I32, 1, "1", err) ||
        series(h, &h->s_residual, "/steps/residual", NC_H5_F64, 1, res_units, err) ||
        series(h, &h->s_converged, "/steps/converged", NC_H5_I32, 1, "1", err) ||
        series(h, &h->s_force, "/steps/contact_force", NC_H5_F64, 3, "N", err) ||
        series(h, &h->s_contact, "/steps/in_contact", NC_H5_I32, 1, "1", err) ||
        series(h, &h->s_near, "/steps/near_interface", NC_H5_I32, 1, "1", err) ||
        series(h, &h->s_gap, "/steps/min_gap", NC_H5_F64, 1, "m", err) ||
        series(h, &h->s_rejected, "/steps/rejected", NC_H5_I32, 1, "1", err) ||
        series(h, &h->e_above, "/energy/above", NC_H5_I32, 1, "1", err))
        goto fail;
    h->keep = (hsize_t)h->mark_rejections;
    if (series(h, &h->r_step, "/rejections/step", NC_H5_I32, 1, "1", err) ||
        series(h, &h->r_attempt, "/rejections/attempt", NC_H5_I32, 1, "1", err) ||
        series(h, &h->r_time, "/rejections/time", NC_H5_F64, 1, "s", err) ||
        series(h, &h->r_dt, "/rejections/dt", NC_H5_F64, 1, "s", err) ||
        series(h, &h->r_next_dt, "/rejections/next_dt", NC_H5_F64, 1, "s", err) ||
        series(h, &h->r_iterations, "/rejections/iterations", NC_H5_I32, 1, "1", err) ||
        series(h, &h->r_residual, "/rejections/residual", NC_H5_F64, 1, res_units, err) ||
        series(h, &h->r_reason, "/rejections/reason", NC_H5_I32, 1, "1", err))
        goto fail;
    h->keep = (hsize_t)h->mark_steps;
    for (int k = 0; k < CPL_HISTORY_ENERGY_SERIES; k++) {
        char name[64];
        snprintf(name, sizeof name, "/energy/%s", energy_names[k]);
        if (series(h, &h->e_series[k], name, NC_H5_F64, 1, "J", err))
            goto fail;
    }
    h->keep = (hsize_t)h->mark_iterations;
    if (write_iterations &&
        (series(h, &h->i_step, "/iterations/step", NC_H5_I32, 1, "1", err) ||
         series(h, &h->i_iteration, "/iterations/iteration", NC_H5_I32, 1, "1", err) ||
         series(h, &h->i_residual, "/iterations/residual", NC_H5_F64, 1, res_units, err) ||
         series(h, &h->i_alpha, "/iterations/alpha", NC_H5_F64, 1, "1", err) ||
         series(h, &h->i_force, "/iterations/contact_force", NC_H5_F64, 3, "N", err) ||
         series(h, &h->i_fem_solved, "/iterations/fem_solved", NC_H5_I32, 1, "1", err) ||
         series(h, &h->i_attempt, "/iterations/attempt", NC_H5_I32, 1, "1", err) ||
         series(h, &h->i_dt, "/iterations/dt", NC_H5_F64, 1, "s", err) ||
         series(h, &h->i_jacobian_miss, "/iterations/jacobian_miss", NC_H5_F64, 1, "1", err) ||
         series(h, &h->i_compliance, "/iterations/compliance", NC_H5_I32, 1, "1", err)))
        goto fail;
    if (nc_h5_attr_string(&h->h5, "/", "scheme", s->scheme == CPL_SCHEME_STRONG ? "strong" : "weak", err) ||
        /* a weak step is not iterated: nothing is relaxed whatever the settings say */
        nc_h5_attr_string(&h->h5, "/", "relaxation",
                          s->scheme == CPL_SCHEME_STRONG ? cpl_relax_settings_method(&s->relax)
                                                         : "none", err) ||
        nc_h5_attr_string(&h->h5, "/", "relaxed_quantity",
                          s->relaxed == CPL_RELAXED_FORCE ? "force" : "displacement_velocity", err) ||
        nc_h5_attr_double(&h->h5, "/", "tolerance", s->tol_abs, err) ||
        nc_h5_attr_double(&h->h5, "/", "work_tolerance", s->work_tol, err) ||
        nc_h5_attr_double(&h->h5, "/", "newton_estimate", s->newton_estimate, err) ||
        nc_h5_attr_double(&h->h5, "/", "interface_compliance", (double)s->interface_compliance, err) ||
        nc_h5_attr_double(&h->h5, "/", "structure_predictor", (double)s->structure_predictor, err) ||
        nc_h5_attr_double(&h->h5, "/", "compliance_proximity", (double)s->compliance_proximity, err) ||
        nc_h5_attr_double(&h->h5, "/", "dt", s->dt_s, err) ||
        nc_h5_attr_double(&h->h5, "/", "dt_min", cpl_loop_settings_dt_min(s), err) ||
        nc_h5_attr_double(&h->h5, "/", "grow_after", (double)s->grow_after, err) ||
        nc_h5_attr_double(&h->h5, "/", "energy_tolerance", s->energy.tol_rel, err) ||
        nc_h5_attr_double(&h->h5, "/", "energy_tolerance_abs", s->energy.tol_abs_j, err) ||
        nc_h5_flush(&h->h5, err))
        goto fail;
    snprintf(path, sizeof path, "%s/iterations.log", dir);
    if (h->resuming) {
        /* the lines after the checkpoint go; later ones are appended */
        if (truncate(path, (off_t)h->mark_log_bytes) != 0) {
            nc_error_set(err, 1, "%s: cannot cut the iterations log back to the checkpoint "
                         "(%ld bytes): %s", path, h->mark_log_bytes, strerror(errno));
            goto fail;
        }
        h->log = fopen(path, "a");
    } else {
        h->log = fopen(path, "w");
    }
    if (!h->log) {
        nc_error_set(err, 1, "%s: cannot %s the iterations log", path,
                     h->resuming ? "reopen" : "create");
        goto fail;
    }
    if (!h->resuming)
        fprintf(h->log, "# step time iterations converged residual dt rejected created_J "
                "input_J\n");
    fflush(h->log);
    return 0;
fail:
    cpl_history_close(h, NULL, NULL, NULL);
    return -1;
}

int cpl_history_iteration(cpl_history *h, const cpl_iteration_record *rec, nc_error *err)
{
    if (!h->open || !h->write_iterations) return 0;
    int32_t step = (int32_t)rec->step, it = rec->iteration, solved = rec->fem_solved,
            attempt = rec->attempt, compliance = rec->compliance;
    return nc_h5_series_append(&h->i_step, &step, err) ||
           nc_h5_series_append(&h->i_iteration, &it, err) ||
           nc_h5_series_append(&h->i_residual, &rec->residual, err) ||
           nc_h5_series_append(&h->i_alpha, &rec->alpha, err) ||
           nc_h5_series_append(&h->i_force, rec->contact_force, err) ||
           nc_h5_series_append(&h->i_fem_solved, &solved, err) ||
           nc_h5_series_append(&h->i_attempt, &attempt, err) ||
           nc_h5_series_append(&h->i_dt, &rec->dt_s, err) ||
           nc_h5_series_append(&h->i_jacobian_miss, &rec->jacobian_miss, err) ||
           nc_h5_series_append(&h->i_compliance, &compliance, err) ||
           flush_due(h, err)
               ? -1 : 0;
}

int cpl_history_step(cpl_history *h, const cpl_step_record *rec, nc_error *err)
{
    if (!h->open) return 0;
    int32_t its = rec->iterations, conv = rec->converged, contact = rec->in_contact,
            near = rec->near_interface, rejected = rec->rejected;
    if (nc_h5_series_append(&h->s_time, &rec->time_s, err) ||
        nc_h5_series_append(&h->s_dt, &rec->dt_s, err) ||
        nc_h5_series_append(&h->s_iterations, &its, err) ||
        nc_h5_series_append(&h->s_residual, &rec->residual, err) ||
        nc_h5_series_append(&h->s_converged, &conv, err) ||
        nc_h5_series_append(&h->s_force, rec->contact_force, err) ||
        nc_h5_series_append(&h->s_contact, &contact, err) ||
        nc_h5_series_append(&h->s_near, &near, err) ||
        nc_h5_series_append(&h->s_gap, &rec->min_gap_m, err) ||
        nc_h5_series_append(&h->s_rejected, &rejected, err))
        return -1;
    double ev[CPL_HISTORY_ENERGY_SERIES];
    energy_values(&rec->energy, ev);
    int32_t above = rec->energy.above;
    for (int k = 0; k < CPL_HISTORY_ENERGY_SERIES; k++)
        if (nc_h5_series_append(&h->e_series[k], &ev[k], err)) return -1;
    if (nc_h5_series_append(&h->e_above, &above, err) || flush_due(h, err)) return -1;
    fprintf(h->log, "%ld %.9g %d %d %.6e %.9g %d %.6e %.6e\n", rec->step, rec->time_s,
            rec->iterations, rec->converged, rec->residual, rec->dt_s, rec->rejected,
            rec->energy.created_j, rec->energy.input_j);
    if (rec->energy.above && h->energy_warned++ == 0)
        fprintf(h->log, "# energy created: step %ld (t = %.9g s): %.6e J created, above the "
                "limit %.6e J (energy_tolerance x input %.6e J + energy_tolerance_abs)\n",
                rec->step, rec->time_s, rec->energy.created_j, rec->energy.limit_j,
                rec->energy.input_j);
    if (fflush(h->log) != 0)
        return nc_error_set(err, 1, "iterations.log: write failed (disk full?)");
    return 0;
}

int cpl_history_reject(cpl_history *h, const cpl_reject_record *rec, nc_error *err)
{
    if (!h->open) return 0;
    int32_t step = (int32_t)rec->step, attempt = rec->attempt, its = rec->iterations,
            reason = (int32_t)rec->reason;
    if (nc_h5_series_append(&h->r_step, &step, err) ||
        nc_h5_series_append(&h->r_attempt, &attempt, err) ||
        nc_h5_series_append(&h->r_time, &rec->time_s, err) ||
        nc_h5_series_append(&h->r_dt, &rec->dt_s, err) ||
        nc_h5_series_append(&h->r_next_dt, &rec->next_dt_s, err) ||
        nc_h5_series_append(&h->r_iterations, &its, err) ||
        nc_h5_series_append(&h->r_residual, &rec->residual, err) ||
        nc_h5_series_append(&h->r_reason, &reason, err) || flush_due(h, err))
        return -1;
    fprintf(h->log, "# rejected step %ld (t = %.9g s, dt = %.9g s, try %d): %s after %d "
            "iterations, residual %.6e; retried with dt = %.9g s%s%s\n", rec->step, rec->time_s,
            rec->dt_s, rec->attempt + 1, cpl_reject_reason_text(rec->reason), rec->iterations,
            rec->residual, rec->next_dt_s, rec->message[0] ? ": " : "", rec->message);
    if (fflush(h->log) != 0)
        return nc_error_set(err, 1, "iterations.log: write failed (disk full?)");
    return 0;
}

void cpl_history_close(cpl_history *h, const cpl_timing *t, const cpl_energy *energy,
                       const cpl_run_status *status)
{
    if (!h->open) return;
    if (t) {
        /* best effort: a failure here must not hide the run's own error */
        hsize_t one = 1;
        double total = t->total_s;
        if (nc_h5_write_units(&h->h5, "/timing/total", NC_H5_F64, 1, &one, &total, "s", NULL) == 0) {
            nc_h5_attr_double(&h->h5, "/timing/total", "wait_fem_s", t->wait_fem_s, NULL);
            nc_h5_attr_double(&h->h5, "/timing/total", "wait_dem_s", t->wait_dem_s, NULL);
            nc_h5_attr_double(&h->h5, "/timing/total", "solver_fem_s", t->solver_fem_s, NULL);
            nc_h5_attr_double(&h->h5, "/timing/total", "solver_dem_s", t->solver_dem_s, NULL);
            nc_h5_attr_double(&h->h5, "/timing/total", "steps", (double)t->steps, NULL);
            nc_h5_attr_double(&h->h5, "/timing/total", "iterations", (double)t->iterations, NULL);
            nc_h5_attr_double(&h->h5, "/timing/total", "fem_solves", (double)t->fem_solves, NULL);
            nc_h5_attr_double(&h->h5, "/timing/total", "dem_solves", (double)t->dem_solves, NULL);
            nc_h5_attr_double(&h->h5, "/timing/total", "fem_repeats_skipped",
                              (double)t->fem_repeats_skipped, NULL);
            nc_h5_attr_double(&h->h5, "/timing/total", "compliance_tries",
                              (double)t->compliance_tries, NULL);
            nc_h5_attr_double(&h->h5, "/timing/total", "compliance_dropped",
                              (double)t->compliance_dropped, NULL);
            nc_h5_attr_double(&h->h5, "/timing/total", "structure_predictions",
                              (double)t->structure_predictions, NULL);
        }
        nc_h5_attr_double(&h->h5, "/", "unconverged_steps", (double)t->unconverged_steps, NULL);
        nc_h5_attr_double(&h->h5, "/", "rejected_attempts", (double)t->rejected_attempts, NULL);
        nc_h5_attr_double(&h->h5, "/", "slow_rejections", (double)t->slow_rejections, NULL);
        nc_h5_attr_double(&h->h5, "/", "contact_backtracks", (double)t->backtracks, NULL);
        nc_h5_attr_double(&h->h5, "/", "work_test_steps", (double)t->work_test_steps, NULL);
        nc_h5_attr_double(&h->h5, "/", "estimate_steps", (double)t->estimate_steps, NULL);
        nc_h5_attr_double(&h->h5, "/", "jacobian_dropped_steps",
                          (double)t->jacobian_dropped_steps, NULL);
        nc_h5_attr_double(&h->h5, "/", "reduced_steps", (double)t->reduced_steps, NULL);
        nc_h5_attr_double(&h->h5, "/", "min_dt_used", t->min_dt_s, NULL);
    }
    if (energy) {
        nc_h5_attr_double(&h->h5, "/", "energy_available", energy->available && energy->started,
                          NULL);
        nc_h5_attr_double(&h->h5, "/", "energy_above_steps", (double)energy->above_steps, NULL);
        nc_h5_attr_double(&h->h5, "/", "energy_first_step", (double)energy->first_step, NULL);
        nc_h5_attr_double(&h->h5, "/", "energy_first_time", energy->first_time_s, NULL);
    }
    if (status) {
        nc_h5_attr_double(&h->h5, "/", "finished", status->finished, NULL);
        nc_h5_attr_double(&h->h5, "/", "reliable", status->reliable, NULL);
        nc_h5_attr_double(&h->h5, "/", "accept_unconverged", status->accept_unconverged, NULL);
        nc_h5_attr_double(&h->h5, "/", "energy_growth", status->energy_growth, NULL);
        nc_h5_attr_double(&h->h5, "/", "accept_energy_growth", status->accept_energy_growth,
                          NULL);
        nc_h5_attr_double(&h->h5, "/", "impulse_loss", status->impulse_loss, NULL);
        nc_h5_attr_double(&h->h5, "/", "accept_impulse_loss", status->accept_impulse_loss, NULL);
        nc_h5_attr_double(&h->h5, "/", "impulse_missed_share", status->impulse_missed_share,
                          NULL);
    }
    nc_h5_series *all[] = {&h->s_time, &h->s_dt, &h->s_iterations, &h->s_residual,
                           &h->s_converged, &h->s_force, &h->s_contact, &h->s_near, &h->s_gap,
                           &h->s_rejected, &h->i_step, &h->i_iteration, &h->i_residual,
                           &h->i_alpha, &h->i_force, &h->i_fem_solved, &h->i_attempt, &h->i_dt,
                           &h->i_jacobian_miss, &h->i_compliance, &h->r_step, &h->r_attempt, &h->r_time, &h->r_dt, &h->r_next_dt,
                           &h->r_iterations, &h->r_residual, &h->r_reason, &h->e_above};
    for (size_t i = 0; i < sizeof all / sizeof *all; i++) nc_h5_series_close(all[i]);
    for (int k = 0; k < CPL_HISTORY_ENERGY_SERIES; k++) nc_h5_series_close(&h->e_series[k]);
    nc_h5_flush(&h->h5, NULL);
    nc_h5_close(&h->h5);
    if (h->log) fclose(h->log);
    h->log = NULL;
    h->open = 0;
}
