/* cpl_config — coupler.json: scheme, time, tolerances, relaxation, efficiency options,
 * step control, participants, timeouts and output settings. */
#include "cpl_config.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "nc_file.h"
#include "nc_json.h"
#include "nc_time.h"

void cpl_config_default(cpl_config *c)
{
    memset(c, 0, sizeof *c);
    cpl_loop_settings_default(&c->loop);
    /* a case without a relaxation method gets Aitken: the unrelaxed plain exchange diverges
     * where the interface map's gain exceeds 1, and plain Newton on the interface (the
     * Jacobian without relaxation) was the less reliable of the two in the study of
     * docs/notes/interface_jacobian.md ("Newton's regime": 59 of 64 runs against 64) */
    nc_error err;
    if (cpl_relax_settings_select(&c->loop.relax, "aitken", &err))
        nc_error_clear(&err);   /* not reached: the method table has Aitken */
    c->connect_timeout_s = 30.0;
    c->reply_timeout_s = 60.0;   /* below the participants' idle timeout (300 s) */
    c->shutdown_timeout_s = 5.0;
    c->write_iterations = 1;
    c->progress_interval_s = 10.0;
}

static int parse_participant(const cJSON *root, const char *where, const char *key,
                             const char *base_dir, cpl_endpoint_config *out, nc_error *err)
{
    char path[512];
    const cJSON *obj = NULL;
    if (nc_json_object_opt(root, where, key, &obj, err)) return -1;
    if (!obj) return 0;   /* may come from the command line */
    nc_json_path(path, sizeof path, where, key);
    static const char *const keys[] = {"endpoint", "endpoint_file", NULL};
    if (nc_json_check_keys(obj, path, keys, err)) return -1;
    const char *endpoint = NULL, *file = NULL;
    if (nc_json_string_opt(obj, path, "endpoint", NULL, &endpoint, err) ||
        nc_json_string_opt(obj, path, "endpoint_file", NULL, &file, err))
        return -1;
    if (endpoint && file)
        return nc_error_set(err, 1, "%s: give either endpoint or endpoint_file, not both", path);
    if (endpoint) snprintf(out->endpoint, sizeof out->endpoint, "%s", endpoint);
    if (file) nc_file_join(base_dir, file, out->endpoint_file, sizeof out->endpoint_file);
    return 0;
}

/* The relaxation object is read by the relaxation module: its keys depend on the methods. */
static int parse_relaxation(const cJSON *root, const char *where, cpl_relax_settings *r,
                            nc_error *err)
{
    const cJSON *obj = NULL;
    if (nc_json_object_opt(root, where, "relaxation", &obj, err)) return -1;
    if (!obj) return 0;
    char path[512];
    nc_json_path(path, sizeof path, where, "relaxation");
    return cpl_relax_settings_parse(r, obj, path, err);
}

static int parse_efficiency(const cJSON *root, const char *where, cpl_loop_settings *s,
                            nc_error *err)
{
    const cJSON *obj = NULL;
    if (nc_json_object_opt(root, where, "efficiency", &obj, err)) return -1;
    if (!obj) return 0;
    char path[512];
    nc_json_path(path, sizeof path, where, "efficiency");
    static const char *const keys[] = {"far_step", "far_step_factor",
                                       "skip_fem_without_contact", "contact_force_threshold",
                                       NULL};
    return nc_json_check_keys(obj, path, keys, err) ||
           nc_json_bool_opt(obj, path, "far_step", s->far_step, &s->far_step, err) ||
           nc_json_number_range_opt(obj, path, "far_step_factor", s->far_step_factor, 1.0,
                                    1e6, &s->far_step_factor, err) ||
           nc_json_bool_opt(obj, path, "skip_fem_without_contact",
                            s->skip_fem_without_contact, &s->skip_fem_without_contact, err) ||
           nc_json_number_range_opt(obj, path, "contact_force_threshold",
                                    s->contact_force_threshold_n, 0.0, INFINITY,
                                    &s->contact_force_threshold_n, err)
               ? -1 : 0;
}

/* step_control: dt_min (absent: dt / 64, resolved by the loop), grow_after, reject_slow. */
static int parse_step_control(const cJSON *root, const char *where, cpl_loop_settings *s,
                              nc_error *err)
{
    const cJSON *obj = NULL;
    if (nc_json_object_opt(root, where, "step_control", &obj, err)) return -1;
    if (!obj) return 0;
    char path[512];
    nc_json_path(path, sizeof path, where, "step_control");
    static const char *const keys[] = {"dt_min", "grow_after", "reject_slow", NULL};
    long grow = s->grow_after;
    if (nc_json_check_keys(obj, path, keys, err) ||
        nc_json_number_range_opt(obj, path, "dt_min", s->dt_min_s, 1e-300, INFINITY,
                                 &s->dt_min_s, err) ||
        nc_json_int_opt(obj, path, "grow_after", grow, 1, 1000000000L, &grow, err) ||
        nc_json_bool_opt(obj, path, "reject_slow", s->reject_slow, &s->reject_slow, err))
        return -1;
    s->grow_after = (int)grow;
    return 0;
}

static int parse_timeouts(const cJSON *root, const char *where, cpl_config *c, nc_error *err)
{
    const cJSON *obj = NULL;
    if (nc_json_object_opt(root, where, "timeouts", &obj, err)) return -1;
    if (!obj) return 0;
    char path[512];
    nc_json_path(path, sizeof path, where, "timeouts");
    static const char *const keys[] = {"connect", "reply", "shutdown", NULL};
    return nc_json_check_keys(obj, path, keys, err) ||
           nc_json_number_range_opt(obj, path, "connect", c->connect_timeout_s, 0.1, 1e6,
                                    &c->connect_timeout_s, err) ||
           nc_json_number_range_opt(obj, path, "reply", c->reply_timeout_s, 0.1, 1e6,
                                    &c->reply_timeout_s, err) ||
           nc_json_number_range_opt(obj, path, "shutdown", c->shutdown_timeout_s, 0.1, 1e6,
                                    &c->shutdown_timeout_s, err)
               ? -1 : 0;
}

/* checkpoint: interval_s, simulated time between checkpoints (absent or 0: none) */
static int parse_checkpoint(const cJSON *root, const char *where, cpl_loop_settings *s,
                            nc_error *err)
{
    const cJSON *obj = NULL;
    if (nc_json_object_opt(root, where, "checkpoint", &obj, err)) return -1;
    if (!obj) return 0;
    char path[512];
    nc_json_path(path, sizeof path, where, "checkpoint");
    static const char *const keys[] = {"interval_s", NULL};
    return nc_json_check_keys(obj, path, keys, err) ||
           nc_json_number_range_opt(obj, path, "interval_s", s->checkpoint_interval_s, 0.0,
                                    1e12, &s->checkpoint_interval_s, err)
               ? -1 : 0;
}

static int parse_output(const cJSON *root, const char *where, cpl_config *c, nc_error *err)
{
    const cJSON *obj = NULL;
    if (nc_json_object_opt(root, where, "output", &obj, err)) return -1;
    if (!obj) return 0;
    char path[512];
    nc_json_path(path, sizeof path, where, "output");
    static const char *const keys[] = {"iterations", "progress_interval", NULL};
    return nc_json_check_keys(obj, path, keys, err) ||
           nc_json_bool_opt(obj, path, "iterations", c->write_iterations, &c->write_iterations,
                            err) ||
           nc_json_number_range_opt(obj, path, "progress_interval", c->progress_interval_s,
                                    0.0, 1e6, &c->progress_interval_s, err)
               ? -1 : 0;
}

int cpl_config_parse(cpl_config *c, const cJSON *root, const char *where, const char *base_dir,
                     nc_error *err)
{
    static const char *const keys[] = {
        "fem", "dem", "scheme", "dt", "start_time", "end_time", "max_steps", "tolerance",
        "relative_tolerance", "work_tolerance", "newton_estimate", "max_iterations",
        "on_max_iterations", "relaxation", "relaxed_quantity", "predictor", "efficiency", "step_control", "accept_unconverged",
        "energy_tolerance", "energy_tolerance_abs", "accept_energy_growth",
        "stop_on_energy_growth", "impulse_tolerance",
        "accept_impulse_loss", "interface_jacobian", "interface_compliance",
        "structure_predictor", "compliance_proximity", "verify_restore",
        "contact_backtracking", "jacobian_check", "timeouts", "output", "checkpoint",
        "comment", NULL};
    static const char *const schemes[] = {"weak", "strong", NULL};
    static const char *const policies[] = {"accept", "stop", NULL};
    static const char *const quantities[] = {"displacement_velocity", "force", NULL};
    static const char *const predictors[] = {"constant", "linear", "quadratic", NULL};
    cpl_loop_settings *s = &c->loop;
    int scheme = s->scheme, policy = s->on_max_iterations, quantity = s->relaxed,
        predictor = s->predictor;
    const cJSON *predictor_item = cJSON_GetObjectItemCaseSensitive(root, "predictor");
    const int predictor_given = predictor_item && !cJSON_IsNull(predictor_item);
    long max_it = s->max_iterations, max_steps = s->max_steps,
         backtracking = s->contact_backtracking, check_interval = s->jacobian_check_interval;
    if (nc_json_check_keys(root, where, keys, err) ||
        parse_participant(root, where, "fem", base_dir, &c->fem, err) ||
        parse_participant(root, where, "dem", base_dir, &c->dem, err) ||
        nc_json_choice_opt(root, where, "scheme", schemes, -1, &scheme, err) ||
        nc_json_positive(root, where, "dt", &s->dt_s, err) ||
        nc_json_number_opt(root, where, "start_time", 0.0, &s->start_time_s, err) ||
        nc_json_number(root, where, "end_time", &s->end_time_s, err) ||
        nc_json_int_opt(root, where, "max_steps", 0, 0, 1000000000L, &max_steps, err) ||
        nc_json_number_range_opt(root, where, "tolerance", s->tol_abs, 1e-300, INFINITY,
                                 &s->tol_abs, err) ||
        nc_json_number_range_opt(root, where, "relative_tolerance", s->tol_rel, 0.0, 1.0,
                                 &s->tol_rel, err) ||
        nc_json_number_range_opt(root, where, "work_tolerance", s->work_tol, 0.0, 1.0,
                                 &s->work_tol, err) ||
        nc_json_number_range_opt(root, where, "newton_estimate", s->newton_estimate, 0.0, 0.5,
                                 &s->newton_estimate, err) ||
        nc_json_int_opt(root, where, "max_iterations", max_it, 1, 100000, &max_it, err) ||
        nc_json_choice_opt(root, where, "on_max_iterations", policies, policy, &policy, err) ||
        nc_json_choice_opt(root, where, "relaxed_quantity", quantities, quantity, &quantity,
                           err) ||
        nc_json_choice_opt(root, where, "predictor", predictors, predictor, &predictor, err) ||
        parse_relaxation(root, where, &s->relax, err) ||
        parse_efficiency(root, where, s, err) ||
        parse_step_control(root, where, s, err) ||
        nc_json_bool_opt(root, where, "accept_unconverged", c->accept_unconverged,
                         &c->accept_unconverged, err) ||
        nc_json_number_range_opt(root, where, "energy_tolerance", s->energy.tol_rel, 0.0,
                                 INFINITY, &s->energy.tol_rel, err) ||
        nc_json_number_range_opt(root, where, "energy_tolerance_abs", s->energy.tol_abs_j, 0.0,
                                 INFINITY, &s->energy.tol_abs_j, err) ||
        nc_json_bool_opt(root, where, "accept_energy_growth", c->accept_energy_growth,
                         &c->accept_energy_growth, err) ||
        nc_json_bool_opt(root, where, "stop_on_energy_growth", s->stop_on_energy_growth,
                         &s->stop_on_energy_growth, err) ||
        nc_json_number_range_opt(root, where, "impulse_tolerance", s->impulse.tol_rel, 0.0, 1.0,
                                 &s->impulse.tol_rel, err) ||
        nc_json_bool_opt(root, where, "accept_impulse_loss", c->accept_impulse_loss,
                         &c->accept_impulse_loss, err) ||
        nc_json_bool_opt(root, where, "interface_jacobian", s->interface_jacobian,
                         &s->interface_jacobian, err) ||
        nc_json_bool_opt(root, where, "interface_compliance", s->interface_compliance,
                         &s->interface_compliance, err) ||
        nc_json_bool_opt(root, where, "structure_predictor", s->structure_predictor,
                         &s->structure_predictor, err) ||
        nc_json_bool_opt(root, where, "compliance_proximity", s->compliance_proximity,
                         &s->compliance_proximity, err) ||
        nc_json_bool_opt(root, where, "verify_restore", s->verify_restore, &s->verify_restore,
                         err) ||
        nc_json_int_opt(root, where, "contact_backtracking", backtracking, 0, 30, &backtracking,
                        err) ||
        nc_json_int_opt(root, where, "jacobian_check", check_interval, 0, 1000000000L,
                        &check_interval, err) ||
        parse_timeouts(root, where, c, err) ||
        parse_output(root, where, c, err) ||
        parse_checkpoint(root, where, s, err))
        return -1;
    if (s->stop_on_energy_growth && c->accept_energy_growth)
        return nc_error_set(err, 1, "%s: stop_on_energy_growth and accept_energy_growth are both "
                            "true: a run cannot both stop and accept when the energy guard "
                            "fires", where);
    s->scheme = (cpl_scheme)scheme;
    s->on_max_iterations = (cpl_maxit_policy)policy;
    s->relaxed = (cpl_relaxed_quantity)quantity;
    /* the quadratic guess saves strong iterations; a weak step keeps its guess, and with a
     * damped contact the quadratic one made it create energy (coupler/README.md) */
    if (!predictor_given)
        predictor = s->scheme == CPL_SCHEME_STRONG ? CPL_PREDICT_QUADRATIC : CPL_PREDICT_LINEAR;
    s->predictor = (cpl_predictor)predictor;
    s->max_iterations = (int)max_it;
    s->max_steps = max_steps;
    s->contact_backtracking = (int)backtracking;
    s->jacobian_check_interval = (int)check_interval;
    if (cpl_loop_settings_check(s, where, err)) return -1;
    /* dt against the float spacing of the times it is added to (nc_time.h), and a bound on
     * the number of steps, so that a run that could not advance or never end is refused */
    char what[CPL_PATH_MAX + 8];
    long steps;
    nc_json_path(what, sizeof what, where, "dt");
    double t_max = fmax(fabs(s->start_time_s), fabs(s->end_time_s));
    char what_min[CPL_PATH_MAX + 64];
    snprintf(what_min, sizeof what_min, "%s (its smallest value under step_control)", what);
    if (nc_time_check_step(s->dt_s, t_max, what, err) ||
        nc_time_step_count(s->end_time_s - s->start_time_s, s->dt_s, NC_TIME_MAX_STEPS, what,
                           &steps, err) ||
        nc_time_check_step(cpl_loop_settings_dt_min(s), t_max, what_min, err))
        return -1;
    return 0;
}

int cpl_config_load(cpl_config *c, const char *path, nc_error *err)
{
    cJSON *root = NULL;
    if (nc_json_load_file(path, &root, err)) return -1;
    char base[CPL_PATH_MAX];
    nc_file_dir(path, base, sizeof base);
    int rc = cpl_config_parse(c, root, path, base, err);
    cJSON_Delete(root);
    return rc;
}
