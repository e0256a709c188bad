/* fem_run — standalone driver: static load stepping or implicit dynamics to end_time,
 * with monitor rows every step and full output every output interval (see fem_run.h). */
#include "fem_run.h"
#include "fem_output.h"
#include "nc_clock.h"

#include <math.h>
#include <string.h>

/* A standalone step whose Newton iteration failed: what the user can change. (A coupled
 * run's coupler retries such a step with a smaller Δt by itself.) */
static void newton_hint(nc_error *err)
{
    if (!err || err->code != FEM_ERR_NEWTON) return;
    char first[NC_ERROR_MESSAGE_MAX];
    snprintf(first, sizeof first, "%s", err->message);
    nc_error_set(err, FEM_ERR_NEWTON, "%s; a smaller analysis.dt_s (load_steps for statics) or "
                 "a larger analysis.max_iterations may converge: a slack net snapping taut "
                 "under its own weight can need either", first);
}

/* Whether any element carries mass: the pseudo-time steps of fem_analysis_settle need it. */
static int model_has_mass(const fem_model *m)
{
    for (int e = 0; e < m->n_elements; e++)
        if (m->rhoA[e] > 0.0) return 1;
    return 0;
}

/* A static load increment whose Newton iteration failed (or met a matrix that nothing holds
 * in some direction: slack cables) solved again by pseudo-time steps from the last
 * equilibrium (fem_analysis_settle); err keeps Newton's failure when that fails too or the
 * model has no mass. */
static int static_increment(fem_analysis *s, double lambda, fem_run_summary *sum, nc_error *err)
{
    if (fem_analysis_static(s, lambda, err) == 0) {
        sum->newton_iterations += s->stats.iterations;
        return 0;
    }
    if (err->code != FEM_ERR_NEWTON && err->code != FEM_ERR_SINGULAR) return -1;
    char first[NC_ERROR_MESSAGE_MAX];
    snprintf(first, sizeof first, "%s", err->message);
    if (!model_has_mass(s->m))
        return nc_error_set(err, err->code, "%s; the model has no mass (density_kg_m3 0), so the "
                            "increment cannot be solved by pseudo-time steps either", first);
    int iterations = 0, steps = 0;
    nc_error again;
    nc_error_clear(&again);
    int rc = fem_analysis_settle(s, lambda, &iterations, &steps, &again);
    sum->newton_iterations += iterations;
    if (rc) {
        nc_error_set(err, again.code, "%s; and by pseudo-time steps: %s", first, again.message);
        return -1;
    }
    nc_error_clear(err);
    s->cur.step++;
    s->cur.time_s = lambda;
    sum->settled_increments++;
    return 0;
}

int fem_run_initial_state(fem_analysis *s, fem_run_summary *sum, nc_error *err)
{
    const fem_model *m = s->m;
    sum->initial_iterations = -1;
    sum->initial_max_displacement_node = -1;
    if (m->settings.type != FEM_DYNAMIC) return 0;
    if (m->settings.initial_static) {
        if (fem_analysis_initial_equilibrium(s, &sum->initial_iterations, &sum->initial_steps,
                                             err))
            return -1;
        sum->initial_max_displacement_m = 0.0;
        for (int i = 0; i < m->n_nodes; i++) {
            const double *u = s->cur.u + 3 * i;
            double r = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
            if (r > sum->initial_max_displacement_m || sum->initial_max_displacement_node < 0) {
                sum->initial_max_displacement_m = r;
                sum->initial_max_displacement_node = i;
            }
        }
    }
    return fem_analysis_initial_acceleration(s, err);
}

int fem_run_standalone(const fem_model *m, const char *output_dir,
                       const volatile sig_atomic_t *stop, const fem_settle_watch *watch,
                       fem_run_summary *summary, nc_error *err)
{
    double t0 = nc_clock_now_s();
    fem_run_summary sum;
    memset(&sum, 0, sizeof sum);
    fem_analysis s;
    fem_output out;
    memset(&out, 0, sizeof out);
    out.max_u_node = -1;
    int rc = -1;
    if (fem_analysis_init(&s, m, err)) goto done;
    if (watch) s.settle_watch = *watch;
    s.settle_watch.stop = stop;
    if (fem_output_open(&out, m, output_dir, err)) goto done;
    const fem_settings *set = &m->settings;
    long written_step = -1;
    if (set->type == FEM_STATIC) {
        /* load factor as "time": 0 (reference state), 1/n, ..., 1 */
        if (fem_output_monitor(&out, &s, 0.0, err) || fem_output_step(&out, &s, 0.0, err)) goto done;
        written_step = 0;
        for (int k = 1; k <= set->load_steps; k++) {
            if (stop && *stop) { rc = 1; goto done; }
            double lambda = (double)k / set->load_steps;
            if (static_increment(&s, lambda, &sum, err)) {
                newton_hint(err);
                goto done;
            }
            fem_analysis_update_axial(&s);
            sum.steps++;
            sum.final_time_s = lambda;
            if (fem_output_monitor(&out, &s, lambda, err)) goto done;
            if (k % set->output_interval == 0 || k == set->load_steps) {
                if (fem_output_step(&out, &s, lambda, err)) goto done;
                written_step = k;
            }
            if (fem_output_write_due(&out, err)) goto done;
        }
        sum.final_time_s = 1.0;
    } else {
        if (fem_run_initial_state(&s, &sum, err)) goto done;
        if (fem_output_monitor(&out, &s, 0.0, err) || fem_output_step(&out, &s, 0.0, err)) goto done;
        written_step = 0;
        long n_steps = (long)ceil(set->end_time_s / set->dt_s - 1e-9);
        for (long k = 1; k <= n_steps; k++) {
            if (stop && *stop) { rc = 1; break; }
            if (fem_analysis_step(&s, set->dt_s, err)) {
                newton_hint(err);
                goto done;
            }
            s.cur.time_s = k * set->dt_s;   /* no drift from repeated sums */
            sum.steps++;
            sum.newton_iterations += s.stats.iterations;
            sum.final_time_s = s.cur.time_s;   /* what a failed run reached */
            fem_analysis_update_axial(&s);   /* every step: the peak forces (fem_output_monitor) */
            if (fem_output_monitor(&out, &s, s.cur.time_s, err)) goto done;
            if (k % set->output_interval == 0) {
                if (fem_output_step(&out, &s, s.cur.time_s, err)) goto done;
                written_step = k;
            }
            if (fem_output_write_due(&out, err)) goto done;
        }
        if (written_step != s.cur.step) {
            fem_analysis_update_axial(&s);
            if (fem_output_step(&out, &s, s.cur.time_s, err)) goto done;
        }
        sum.final_time_s = s.cur.time_s;
        if (rc != 1) rc = 0;
        goto done;
    }
    rc = 0;
done:
    /* the rows still in memory and the run's summary in fem.h5, before the printed one: a run
     * (or a stopped one) whose results could not be written failed, and says why; an earlier
     * error is said instead */
    if (rc >= 0 && fem_output_finish(&out, err)) rc = -1;
    sum.output_steps = out.n_out;
    /* the run's largest |u| over every step, not the last step's */
    sum.max_displacement_m = out.max_u_node >= 0 ? out.max_u_m : 0.0;
    sum.max_displacement_time_s = out.max_u_node >= 0 ? out.max_u_time_s : -1.0;
    sum.max_displacement_node = out.max_u_node;
    sum.overload = summary ? summary->overload : NULL;
    sum.overloaded_elements = fem_output_overload(&out, m, sum.overload);
    if (s.m && s.cur.u) sum.stats = s.stats;   /* not when the set-up failed (out of memory) */
    fem_output_close(&out);
    fem_analysis_free(&s);
    sum.wall_s = nc_clock_now_s() - t0;
    if (summary) *summary = sum;
    return rc;
}
