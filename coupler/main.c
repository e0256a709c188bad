/* coupler — drives a FEM and a DEM participant through the netcouple protocol.
 *
 *   coupler coupler.json [--output DIR] [--fem-endpoint EP] [--dem-endpoint EP]
 *           [--fem-endpoint-file PATH] [--dem-endpoint-file PATH] [--endpoint-wait S]
 *           [--quiet] [--progress-file PATH] [--resume]
 *
 * Checkpoints (coupler.json "checkpoint", both participants announcing "checkpoint"): after
 * both participants saved theirs, checkpoint/coupler_<name>.h5 (cpl_checkpoint.h) and the
 * manifest checkpoint/latest.json in the output folder; --resume continues from the
 * manifest's checkpoint.
 *
 * Exit codes: 0 success, 1 input/participant/coupling failure, 3 finished but with accepted
 * unconverged steps, with energy created beyond energy_tolerance or with interface impulse
 * the structure missed beyond impulse_tolerance (results not reliable; 0 instead when
 * coupler.json sets accept_unconverged, accept_energy_growth, respectively
 * accept_impulse_loss), or stopped at the step its energy guard fired at
 * (stop_on_energy_growth), 130 interrupted (SIGINT), 143 terminated (SIGTERM). See
 * coupler/README.md.
 */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "cpl_checkpoint.h"
#include "cpl_config.h"
#include "cpl_heartbeat.h"
#include "cpl_history.h"
#include "cpl_interface.h"
#include "cpl_loop.h"
#include "cpl_progress.h"
#include "cpl_remote.h"
#include "nc_clock.h"
#include "nc_file.h"
#include "nc_json.h"
#include "nc_signal.h"

static void usage(FILE *out)
{
    fprintf(out,
            "usage: coupler coupler.json [--output DIR] [--fem-endpoint EP] [--dem-endpoint EP]\n"
            "               [--fem-endpoint-file PATH] [--dem-endpoint-file PATH]\n"
            "               [--endpoint-wait S] [--quiet] [--progress-file PATH] [--resume]\n"
            "       coupler coupler.json --check\n"
            "Couples a FEM and a DEM participant (weak or strong scheme, see coupler/README.md).\n"
            "  --output DIR        results folder (coupling.h5, iterations.log); default '.'\n"
            "  --fem-endpoint EP   override fem.endpoint of coupler.json (e.g. tcp://127.0.0.1:5555)\n"
            "  --dem-endpoint EP   override dem.endpoint\n"
            "  --fem-endpoint-file PATH, --dem-endpoint-file PATH\n"
            "                      read the endpoint from the file the participant writes,\n"
            "                      waiting for it (overrides coupler.json, not --*-endpoint)\n"
            "  --endpoint-wait S   how long to wait for an endpoint file (default:\n"
            "                      timeouts.connect of coupler.json)\n"
            "  --quiet             only warnings, errors and the final summary\n"
            "  --progress-file PATH  keep PATH up to date with the run's state and status line\n"
            "                      (a heartbeat: rewritten every step and every second while\n"
            "                      waiting for a participant; scripts/run_case.sh reads it)\n"
            "  --resume            continue the run in --output DIR from its last complete\n"
            "                      checkpoint (DIR/checkpoint/latest.json); the participants\n"
            "                      must be started as for the original run\n"
            "  --check             read and check coupler.json, print its warnings and run\n"
            "                      nothing: exit 0 when it is valid, 1 with the error\n");
}

/* A run that finished with accepted unconverged steps or created energy (not opted in). */
enum { EXIT_UNRELIABLE = 3 };

/* A participant seen by the loop through a wrapper that marks its requests as waits for the
 * heartbeat and keeps what the DEM's replies say for the status line. */
typedef struct watched {
    cpl_participant inner;
    struct app *a;
    cpl_remote *remote;
} watched;

typedef struct app {
    cpl_config cfg;
    const char *config_path, *output_dir, *fem_ep_arg, *dem_ep_arg, *progress_path;
    const char *fem_ep_file_arg, *dem_ep_file_arg;   /* --fem-endpoint-file, --dem-... */
    double endpoint_wait_s;     /* --endpoint-wait; 0: timeouts.connect */
    int quiet;
    cpl_remote fem, dem;
    int fem_open, dem_open;
    cpl_mesh mesh;
    cpl_history history;
    cpl_progress progress;
    cpl_heartbeat *heartbeat;       /* NULL without --progress-file */
    int heartbeat_warned;
    cpl_progress_watch watch;       /* from the DEM's last solve; deflection from the loop */
    watched fem_w, dem_w;
    cpl_loop *loop;
    char fem_ep[1024], dem_ep[1024];   /* resolved endpoints ("" while unknown) */
    const volatile sig_atomic_t *stop_signal;   /* 0, or SIGINT / SIGTERM once received */
    int resume;                     /* --resume */
    char ckpt_name[64];             /* the checkpoint resumed from (--resume) */
    char ckpt_newest[64];           /* the newest checkpoint (kept with the next one) */
    long ckpt_step;
    int check_only;                 /* --check: read and check coupler.json, run nothing */
} app;

static int observe_iteration(void *ctx, const cpl_iteration_record *rec, nc_error *err)
{
    app *a = ctx;
    return cpl_history_iteration(&a->history, rec, err);
}

/* The heartbeat's state and status; a failing write is reported once and does not stop the
 * run (the launcher then takes the coupler for stalled only if it stops writing for long). */
static void beat(app *a, const char *state)
{
    if (!a->heartbeat) return;
    char status[512];
    cpl_progress_status(&a->progress, status, sizeof status);
    nc_error err;
    if (cpl_heartbeat_update(a->heartbeat, state, status, &err) && !a->heartbeat_warned++)
        cpl_progress_message(&a->progress, "coupler: warning: %s", err.message);
}

static int observe_step(void *ctx, const cpl_step_record *rec, nc_error *err)
{
    app *a = ctx;
    if (cpl_history_step(&a->history, rec, err)) return -1;
    /* the largest deflection of the interface nodes in the accepted state */
    const double *u = cpl_loop_displacement(a->loop);
    double max2 = 0.0;
    for (size_t i = 0; i < a->mesh.n_nodes; i++) {
        double d2 = u[3 * i] * u[3 * i] + u[3 * i + 1] * u[3 * i + 1] + u[3 * i + 2] * u[3 * i + 2];
        if (d2 > max2) max2 = d2;
    }
    a->watch.deflection_m = sqrt(max2);
    cpl_progress_set_watch(&a->progress, &a->watch);
    cpl_progress_step(&a->progress, rec, a->cfg.loop.scheme == CPL_SCHEME_STRONG);
    beat(a, "running");
    return 0;
}

static int watched_begin(void *ctx, const cpl_call *call, nc_error *err)
{
    watched *w = ctx;
    cpl_heartbeat_wait_begin(w->a->heartbeat, w->inner.name, w->a->cfg.reply_timeout_s);
    int rc = w->inner.begin_step(w->inner.ctx, call, err);
    cpl_heartbeat_wait_end(w->a->heartbeat);
    return rc;
}

static int watched_solve(void *ctx, const cpl_call *call, const double *in0, const double *in1,
                         double *out0, double *out1, cpl_solve_info *info, nc_error *err)
{
    watched *w = ctx;
    app *a = w->a;
    cpl_heartbeat_wait_begin(a->heartbeat, w->inner.name, a->cfg.reply_timeout_s);
    int rc = w->inner.solve(w->inner.ctx, call, in0, in1, out0, out1, info, err);
    cpl_heartbeat_wait_end(a->heartbeat);
    if (rc == 0 && w->remote->kind == CPL_REMOTE_DEM) {
        /* the last solve of a step is the accepted one */
        a->watch.contacts = info->contacts;
        a->watch.kinetic_energy_j = info->energy.kinetic_j;
        a->watch.max_speed_m_s = proto_message_value(&w->remote->reply, "max_particle_speed_m_s",
                                                     NAN);
    }
    return rc;
}

static int watched_accept(void *ctx, const cpl_call *call, nc_error *err)
{
    watched *w = ctx;
    cpl_heartbeat_wait_begin(w->a->heartbeat, w->inner.name, w->a->cfg.reply_timeout_s);
    int rc = w->inner.accept(w->inner.ctx, call, err);
    cpl_heartbeat_wait_end(w->a->heartbeat);
    return rc;
}

static int watched_checkpoint(void *ctx, const cpl_call *call, const char *name, nc_error *err)
{
    watched *w = ctx;
    cpl_heartbeat_wait_begin(w->a->heartbeat, w->inner.name, w->a->cfg.reply_timeout_s);
    int rc = w->inner.checkpoint(w->inner.ctx, call, name, err);
    cpl_heartbeat_wait_end(w->a->heartbeat);
    return rc;
}

static int watched_resume(void *ctx, const cpl_call *call, const char *name, nc_error *err)
{
    watched *w = ctx;
    cpl_heartbeat_wait_begin(w->a->heartbeat, w->inner.name, w->a->cfg.reply_timeout_s);
    int rc = w->inner.resume(w->inner.ctx, call, name, err);
    cpl_heartbeat_wait_end(w->a->heartbeat);
    return rc;
}

static int watched_post(void *ctx, cpl_command command, const cpl_call *call, nc_error *err)
{
    watched *w = ctx;
    cpl_heartbeat_wait_begin(w->a->heartbeat, w->inner.name, w->a->cfg.reply_timeout_s);
    int rc = w->inner.post(w->inner.ctx, command, call, err);
    cpl_heartbeat_wait_end(w->a->heartbeat);
    return rc;
}

static int watched_await(void *ctx, nc_error *err)
{
    watched *w = ctx;
    cpl_heartbeat_wait_begin(w->a->heartbeat, w->inner.name, w->a->cfg.reply_timeout_s);
    int rc = w->inner.await(w->inner.ctx, err);
    cpl_heartbeat_wait_end(w->a->heartbeat);
    return rc;
}

static cpl_participant watch_participant(app *a, watched *w, cpl_remote *r)
{
    *w = (watched){cpl_remote_participant(r), a, r};
    const int two_halves = w->inner.post && w->inner.await;
    cpl_participant p = {w->inner.name, w, watched_begin, watched_solve, watched_accept,
                         w->inner.can_jacobian,
                         w->inner.checkpoint ? watched_checkpoint : NULL,
                         w->inner.resume ? watched_resume : NULL,
                         two_halves ? watched_post : NULL, two_halves ? watched_await : NULL,
                         w->inner.can_compliance};
    return p;
}

/* ---- checkpoint and resume -------------------------------------------------------------- */

/* The program's part of the coupler's checkpoint: the loop's state, the history's marks,
 * the counters of the messages (which warnings were already printed). */
static void app_checkpoint_entries(app *a, cpl_ckpt_table *t)
{
    cpl_loop_checkpoint_entries(a->loop, t);
    cpl_history_checkpoint_entries(&a->history, t);
    cpl_ckpt_long(t, "progress", "warnings", &a->progress.warnings);
    cpl_ckpt_long(t, "progress", "energy_warnings", &a->progress.energy_warnings);
    cpl_ckpt_long(t, "progress", "jacobian_warnings", &a->progress.jacobian_warnings);
    cpl_ckpt_long(t, "progress", "rejections", &a->progress.rejections);
    cpl_ckpt_f64(t, "progress", "max_deflection", &a->progress.max_deflection_m, 1);
}

/* A participant's checkpoint file: the name its reply gave (a plain file name), else the
 * convention of netcouple's solvers, <role>_<name>.h5 (protocol/README.md §3.3). */
static void participant_file(const cpl_remote *r, const char *name, char *out, size_t size)
{
    const char *text = r->reply.text;
    if (text[0] && !strchr(text, '/') && strcmp(text, ".") && strcmp(text, ".."))
        snprintf(out, size, "%s", text);
    else
        snprintf(out, size, "%s_%s.h5", r->name, name);
}

static int observe_checkpoint(void *ctx, long step, double time_s, const char *name,
                              nc_error *err)
{
    app *a = ctx;
    char dir[2048], path[2400], manifest[2400];
    snprintf(dir, sizeof dir, "%s/checkpoint", a->output_dir);
    if (nc_file_make_dirs(dir, err)) return -1;
    if (cpl_history_mark(&a->history, err)) return -1;
    cpl_ckpt_table t = {0};
    app_checkpoint_entries(a, &t);
    cpl_checkpoint_path(a->output_dir, name, path, sizeof path);
    int rc = cpl_ckpt_save(&t, path, err);
    cpl_ckpt_table_free(&t);
    if (rc) return -1;
    /* the manifest names the checkpoint only now that all three files are durable */
    char fem_file[PROTO_TEXT_MAX + 8], dem_file[PROTO_TEXT_MAX + 8], coupler_file[128];
    participant_file(&a->fem, name, fem_file, sizeof fem_file);
    participant_file(&a->dem, name, dem_file, sizeof dem_file);
    snprintf(coupler_file, sizeof coupler_file, "coupler_%s.h5", name);
    cJSON *root = cJSON_CreateObject(), *files = cJSON_CreateObject();
    char time_hex[64];
    snprintf(time_hex, sizeof time_hex, "%a", time_s);
    int ok = root && files && cJSON_AddStringToObject(root, "checkpoint", name) &&
             cJSON_AddNumberToObject(root, "step", (double)step) &&
             cJSON_AddNumberToObject(root, "time", time_s) &&
             cJSON_AddStringToObject(root, "time_hex", time_hex) &&
             cJSON_AddStringToObject(files, "coupler", coupler_file) &&
             cJSON_AddStringToObject(files, "fem", fem_file) &&
             cJSON_AddStringToObject(files, "dem", dem_file);
    if (ok) cJSON_AddItemToObject(root, "files", files);
    else cJSON_Delete(files);
    ok = ok && cJSON_AddStringToObject(root, "previous", a->ckpt_newest);
    char *text = ok ? cJSON_Print(root) : NULL;
    cJSON_Delete(root);
    if (!text) return nc_error_set(err, 1, "checkpoint manifest: out of memory");
    size_t len = strlen(text);
    char *with_newline = malloc(len + 2);
    if (with_newline) {
        memcpy(with_newline, text, len);
        memcpy(with_newline + len, "\n", 2);
    }
    free(text);
    if (!with_newline) return nc_error_set(err, 1, "checkpoint manifest: out of memory");
    snprintf(manifest, sizeof manifest, "%s/latest.json", dir);
    rc = nc_file_write_durably(manifest, with_newline, strlen(with_newline), err);
    free(with_newline);
    if (rc) return -1;
    /* keep the two newest coupler checkpoints (the manifest no longer names the third) */
    char keep_new[128], keep_old[128];
    snprintf(keep_new, sizeof keep_new, "coupler_%s.h5", name);
    snprintf(keep_old, sizeof keep_old, "coupler_%s.h5", a->ckpt_newest);
    const char *keep[2] = {keep_new, a->ckpt_newest[0] ? keep_old : NULL};
    nc_ckpt_prune_except(dir, "coupler_", keep, 2);
    snprintf(a->ckpt_newest, sizeof a->ckpt_newest, "%s", name);
    if (!a->quiet)
        cpl_progress_message(&a->progress, "coupler: checkpoint %s (step %ld, t = %.6g s) in "
                             "%s", name, step, time_s, dir);
    return 0;
}

/* A checkpoint name as the protocol allows it (letters, digits, '_', '-'). */
static int valid_name(const char *s)
{
    if (!s[0] || strlen(s) >= 64) return 0;
    for (; *s; s++)
        if (!((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') || (*s >= '0' && *s <= '9') ||
              *s == '_' || *s == '-'))
            return 0;
    return 1;
}

/* --resume: DIR/checkpoint/latest.json names the last complete checkpoint. */
static int read_manifest(app *a, nc_error *err)
{
    char path[2400];
    snprintf(path, sizeof path, "%s/checkpoint/latest.json", a->output_dir);
    if (access(path, F_OK) != 0)
        return nc_error_set(err, 1, "%s: no checkpoint to resume from (the run wrote none: "
                            "coupler.json \"checkpoint\": {\"interval_s\": ...} and both "
                            "participants announcing 'checkpoint' are needed)", path);
    cJSON *root = NULL;
    if (nc_json_load_file(path, &root, err)) return -1;
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(root, "checkpoint");
    const cJSON *step = cJSON_GetObjectItemCaseSensitive(root, "step");
    int rc = 0;
    if (!cJSON_IsString(name) || !valid_name(name->valuestring))
        rc = nc_error_set(err, 1, "%s: checkpoint: expected the checkpoint's name (letters, "
                          "digits, '_', '-')", path);
    else if (!cJSON_IsNumber(step) || step->valuedouble < 0 ||
             step->valuedouble != (double)(long)step->valuedouble)
        rc = nc_error_set(err, 1, "%s: step: expected a whole number >= 0", path);
    if (rc == 0) {
        snprintf(a->ckpt_name, sizeof a->ckpt_name, "%s", name->valuestring);
        a->ckpt_step = (long)step->valuedouble;
        snprintf(a->ckpt_newest, sizeof a->ckpt_newest, "%s", name->valuestring);
    }
    cJSON_Delete(root);
    return rc;
}

/* Loads the coupler's checkpoint into the fresh loop and history marks. */
static int load_checkpoint(app *a, nc_error *err)
{
    char path[2400];
    cpl_checkpoint_path(a->output_dir, a->ckpt_name, path, sizeof path);
    if (cpl_loop_checkpoint_prepare(a->loop, path, err)) return -1;
    cpl_ckpt_table t = {0};
    app_checkpoint_entries(a, &t);
    int rc = cpl_ckpt_load(&t, path, err);
    cpl_ckpt_table_free(&t);
    if (rc || cpl_loop_checkpoint_loaded(a->loop, path, err)) return -1;
    cpl_loop_resumed(a->loop, a->ckpt_name);
    if (cpl_loop_step(a->loop) != a->ckpt_step)
        return nc_error_set(err, 1, "%s: holds step %ld, checkpoint/latest.json says %ld", path,
                            cpl_loop_step(a->loop), a->ckpt_step);
    return 0;
}

static int observe_reject(void *ctx, const cpl_reject_record *rec, nc_error *err)
{
    app *a = ctx;
    if (cpl_history_reject(&a->history, rec, err)) return -1;
    cpl_progress_reject(&a->progress, rec);
    return 0;
}

static int parse_args(app *a, int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        int has_value = i + 1 < argc;
        if (!strcmp(arg, "--help") || !strcmp(arg, "-h")) {
            usage(stdout);
            exit(0);
        } else if (!strcmp(arg, "--quiet")) {
            a->quiet = 1;
        } else if (!strcmp(arg, "--resume")) {
            a->resume = 1;
        } else if (!strcmp(arg, "--check")) {
            a->check_only = 1;
        } else if (!strcmp(arg, "--output") && has_value) {
            a->output_dir = argv[++i];
        } else if (!strcmp(arg, "--fem-endpoint") && has_value) {
            a->fem_ep_arg = argv[++i];
        } else if (!strcmp(arg, "--dem-endpoint") && has_value) {
            a->dem_ep_arg = argv[++i];
        } else if (!strcmp(arg, "--fem-endpoint-file") && has_value) {
            a->fem_ep_file_arg = argv[++i];
        } else if (!strcmp(arg, "--dem-endpoint-file") && has_value) {
            a->dem_ep_file_arg = argv[++i];
        } else if (!strcmp(arg, "--endpoint-wait") && has_value) {
            char *end = NULL;
            a->endpoint_wait_s = strtod(argv[++i], &end);
            if (!end || *end || !(a->endpoint_wait_s > 0.0) || a->endpoint_wait_s > 1e6) {
                fprintf(stderr, "coupler: --endpoint-wait: expected seconds > 0, got '%s'\n",
                        argv[i]);
                return -1;
            }
        } else if (!strcmp(arg, "--progress-file") && has_value) {
            a->progress_path = argv[++i];
        } else if (arg[0] == '-') {
            fprintf(stderr, "coupler: unknown option or missing value: %s\n", arg);
            usage(stderr);
            return -1;
        } else if (!a->config_path) {
            a->config_path = arg;
        } else {
            fprintf(stderr, "coupler: more than one input file: %s\n", arg);
            return -1;
        }
    }
    if (!a->config_path) {
        usage(stderr);
        return -1;
    }
    if (!a->output_dir) a->output_dir = ".";
    return 0;
}

static int resolve_endpoint(app *a, const cpl_endpoint_config *c, const char *arg,
                            const char *file_arg, const char *name, char *out, size_t size,
                            nc_error *err)
{
    if (arg) {
        snprintf(out, size, "%s", arg);
        return 0;
    }
    if (file_arg)
        return cpl_read_endpoint_file(file_arg, a->endpoint_wait_s > 0.0 ? a->endpoint_wait_s
                                                                         : a->cfg.connect_timeout_s,
                                      out, size, a->stop_signal, err);
    if (c->endpoint[0]) {
        snprintf(out, size, "%s", c->endpoint);
        return 0;
    }
    if (c->endpoint_file[0])
        return cpl_read_endpoint_file(c->endpoint_file, a->cfg.connect_timeout_s, out, size,
                                      a->stop_signal, err);
    return nc_error_set(err, 1, "%s: no endpoint for the %s participant (set %s.endpoint or "
                        "%s.endpoint_file, or use --%s-endpoint)", a->config_path, name, name,
                        name, name);
}

/* Tells the participants to stop: both after success, the healthy one(s) after a failure. */
static int shutdown_all(app *a, const cpl_participant *failed)
{
    int rc = 0;
    /* after a stop signal a launcher may be stopping the participants itself (run_case.sh
     * signals all three at once): a dead one must not hold the coupler up for long */
    double timeout_s = a->cfg.shutdown_timeout_s;
    if (*a->stop_signal && timeout_s > 1.0) timeout_s = 1.0;
    cpl_remote *all[2] = {&a->fem, &a->dem};
    int open[2] = {a->fem_open, a->dem_open};
    const char *known[2] = {a->fem_ep, a->dem_ep};
    const char *files[2] = {a->fem_ep_file_arg, a->dem_ep_file_arg};
    for (int i = 0; i < 2; i++) {
        cpl_remote *r = all[i];
        if (!open[i]) {
            /* not connected yet (start-up failed): still ask it to go, if we know where; one
             * started together with the coupler publishes its endpoint file within its own
             * start-up */
            char found[sizeof a->fem_ep] = "";
            const char *endpoint = known[i];
            nc_error ignored;
            if (!endpoint[0] && files[i] &&
                cpl_read_endpoint_file(files[i], timeout_s, found, sizeof found, NULL,
                                       &ignored) == 0)
                endpoint = found;
            if (!endpoint[0]) continue;
            snprintf(r->name, sizeof r->name, "%s", i == 0 ? "fem" : "dem");
            snprintf(r->endpoint, sizeof r->endpoint, "%s", endpoint);
            nc_error err;
            cpl_heartbeat_wait_begin(a->heartbeat, r->name, timeout_s);
            cpl_remote_shutdown(r, timeout_s, &err);
            cpl_heartbeat_wait_end(a->heartbeat);
            proto_message_free(&r->request);
            proto_message_free(&r->reply);
            continue;
        }
        /* the loop knows the participant through its wrapper */
        int is_failed = failed && (failed->ctx == r ||
                                   (failed->ctx == &a->fem_w && r == &a->fem) ||
                                   (failed->ctx == &a->dem_w && r == &a->dem));
        proto_peer_close(r->peer);   /* drop a possibly pending request first */
        r->peer = NULL;
        if (is_failed && !r->alive) continue;
        nc_error err;
        nc_error_clear(&err);
        cpl_heartbeat_wait_begin(a->heartbeat, r->name, timeout_s);
        int failed_shutdown = cpl_remote_shutdown(r, timeout_s, &err);
        cpl_heartbeat_wait_end(a->heartbeat);
        if (failed_shutdown) {
            /* an error line naming it: the launcher blames that participant, not the coupler */
            cpl_progress_message(&a->progress, "coupler: error: %s: did not acknowledge SHUTDOWN: %s",
                                 r->name, err.message);
            rc = -1;
        }
    }
    return rc;
}

/* jacobian_check's findings (cpl_jacobian_check.h); nothing when it was off. */
static void print_jacobian_check(app *a)
{
    const cpl_jacobian_check *j = cpl_loop_jacobian_check(a->loop);
    FILE *o = a->progress.out;
    if (a->cfg.loop.jacobian_check_interval <= 0) return;
    if (!cpl_loop_uses_jacobian(a->loop)) {
        fprintf(o, "coupler: jacobian check: nothing checked, the interface Jacobian was off\n");
        return;
    }
    if (j->checks == 0) {
        fprintf(o, "coupler: jacobian check: nothing checked (%ld extra DEM solves): no checked "
                "step had an iteration with contact followed by another\n", j->solves);
        return;
    }
    fprintf(o, "coupler: jacobian check: %ld linearisations against central differences of the "
            "DEM's step (%ld extra DEM solves): relative miss above %g in %ld, largest %.3g at "
            "step %ld (t = %.9g s) iteration %d%s\n", j->checks, j->solves,
            CPL_JACOBIAN_CHECK_WARN, j->missed, j->worst, j->worst_step, j->worst_time_s,
            j->worst_iteration,
            j->missed ? "; a wrong derivative misses in every check of the contacts it "
                        "belongs to and makes the iteration converge linearly, a single miss "
                        "can be a contact beginning or ending within the probe "
                        "(/iterations/jacobian_miss in coupling.h5)" : "");
}

static void print_timing(app *a)
{
    const cpl_timing *t = cpl_loop_timing(a->loop);
    double own = t->total_s - t->wait_fem_s - t->wait_dem_s;
    FILE *o = a->progress.out;
    fprintf(o, "coupler: %ld steps, %ld iterations (%.2f per step), %ld unconverged steps\n",
            t->steps, t->iterations, t->steps ? (double)t->iterations / (double)t->steps : 0.0,
            t->unconverged_steps);
    if (t->fem_repeats_skipped > 0)
        fprintf(o, "coupler: %ld FEM solves (%ld not sent: the same force without contact "
                "linearisation as the FEM had just solved with in the step, so the answer it "
                "had given), %ld DEM solves\n", t->fem_solves, t->fem_repeats_skipped,
                t->dem_solves);
    if (t->backtracks > 0)
        fprintf(o, "coupler: contact backtracking: %ld extra DEM solves back along steps "
                "that lost a contact\n", t->backtracks);
    if (cpl_loop_uses_compliance(a->loop))
        fprintf(o, "coupler: interface compliance: the DEM solved with the structure's "
                "compliance; %ld of %ld tries went on without it after its search ended a "
                "contact the structure still carried\n",
                t->compliance_dropped, t->compliance_tries);
    if (t->structure_predictions > 0)
        fprintf(o, "coupler: structure predictor: %ld of the %ld FEM solves were the structure's "
                "motion under the last step's force, which began a try\n",
                t->structure_predictions, t->fem_solves);
    if (t->jacobian_dropped_steps > 0)
        fprintf(o, "coupler: interface Jacobian incomplete in %ld steps: the DEM left particles "
                "out of its linearisation\n", t->jacobian_dropped_steps);
    fprintf(o, "coupler: interface Jacobian %s\n",
            cpl_loop_uses_jacobian(a->loop) ? "on: the FEM solved with the DEM's contact linearisation"
                                            : "off: plain exchange of forces and displacements");
    print_jacobian_check(a);
    fprintf(o, "coupler: wall time %.3f s: waiting for fem %.3f s (%.1f%%), for dem %.3f s "
            "(%.1f%%), coupler itself %.3f s (%.1f%%)\n", t->total_s, t->wait_fem_s,
            t->total_s > 0 ? 100.0 * t->wait_fem_s / t->total_s : 0.0, t->wait_dem_s,
            t->total_s > 0 ? 100.0 * t->wait_dem_s / t->total_s : 0.0, own,
            t->total_s > 0 ? 100.0 * own / t->total_s : 0.0);
    if (isfinite(t->solver_fem_s) && isfinite(t->solver_dem_s)) {
        double exchange = t->wait_fem_s + t->wait_dem_s - t->solver_fem_s - t->solver_dem_s;
        fprintf(o, "coupler: fem solve %.3f s, dem solve %.3f s, exchange + coupler %.3f s "
                "(%.1f%%)\n", t->solver_fem_s, t->solver_dem_s, exchange + own,
                t->total_s > 0 ? 100.0 * (exchange + own) / t->total_s : 0.0);
    }
    fflush(o);
}

/* The energy balance line of the summary (cpl_energy.h). */
static void print_energy(app *a)
{
    const cpl_energy *e = cpl_loop_energy(a->loop);
    FILE *o = a->progress.out;
    if (!e->available || !e->started) {
        fprintf(o, "coupler: energy balance: not available (a participant does not report its "
                "energies), energy guard off\n");
        return;
    }
    double limit = e->s.tol_rel * e->input_j + e->s.tol_abs_j;
    fprintf(o, "coupler: energy balance: input %.6g J (largest kinetic + elastic energy), "
            "energy created by the end %+.6g J (%s; the guard fires above %.6g J, "
            "energy_tolerance %.3g); "
            "interface work mismatch %.6g J, dissipated fem %.6g J, dem %.6g J, external work "
            "%.6g J, closure %.3g J\n", e->input_j, e->created_j,
            e->created_j > limit ? "above the limit"
            : e->created_j > 0.0 ? "within the limit" : "none: the balance lost energy",
            limit, e->s.tol_rel, e->sum_mismatch_j, e->sum_fem_diss_j, e->sum_dem_diss_j,
            e->sum_ext_j, e->closure_j);
}

/* The interface's momentum balance line of the summary (cpl_impulse.h). */
static void print_impulse(app *a)
{
    const cpl_impulse *m = cpl_loop_impulse(a->loop);
    FILE *o = a->progress.out;
    if (!cpl_loop_uses_jacobian(a->loop)) return;   /* the plain exchange passes F on as it is */
    double given = sqrt(m->given_ns[0] * m->given_ns[0] + m->given_ns[1] * m->given_ns[1] +
                        m->given_ns[2] * m->given_ns[2]);
    fprintf(o, "coupler: interface impulse: the particles' contact forces gave the structure "
            "%.6g N s (%.6g N s summed step by step), the structure's linearised force "
            "differed by %.6g N s: %.3g%% (the guard fires above impulse_tolerance %.3g%%)\n",
            given, m->given_abs_ns, m->given_abs_ns * cpl_impulse_missed_share(m),
            100.0 * cpl_impulse_missed_share(m), 100.0 * m->s.tol_rel);
}

/* The impulse guard's verdict when it fired (cpl_impulse.h). */
static void print_impulse_verdict(app *a)
{
    const cpl_impulse *m = cpl_loop_impulse(a->loop);
    /* the structure solved with F − correction: a correction along F took impulse away */
    const double along = m->missed_ns[0] * m->given_ns[0] + m->missed_ns[1] * m->given_ns[1] +
                         m->missed_ns[2] * m->given_ns[2];
    fprintf(a->progress.out,
            "coupler: results are NOT reliable: the force the structure solved with carried "
            "%.3g%% %s impulse than the particles' contact forces (%.6g of %.6g N s; "
            "above impulse_tolerance %.3g%% from step %ld, t = %.6g s): the coupling did not "
            "pass the contact's momentum on (%s); %s\n",
            100.0 * cpl_impulse_missed_share(m), along >= 0.0 ? "less" : "more",
            m->given_abs_ns * cpl_impulse_missed_share(m),
            m->given_abs_ns, 100.0 * m->s.tol_rel, m->first_step, m->first_time_s,
            a->cfg.loop.scheme == CPL_SCHEME_WEAK
                ? "weak coupling, one exchange per step, with a contact too stiff for the "
                  "structure's nodes at this dt: the strong scheme passes it on"
                : "steps accepted far from converged",
            a->cfg.accept_impulse_loss
                ? "accepted because coupler.json sets accept_impulse_loss"
                : "exit status 3 (coupler.json \"accept_impulse_loss\": true accepts it with "
                  "exit status 0)");
}

/* The guard's verdict when it fired: the last line of the summary (of a run that did not
 * finish, the line before the error). */
static void print_energy_verdict(app *a, int finished)
{
    const cpl_energy *e = cpl_loop_energy(a->loop);
    FILE *o = a->progress.out;
    fprintf(o, "coupler: results are NOT reliable: the run created energy: %.6g J at step %ld "
            "(t = %.6g s), above the limit %.6g J (%ld steps above it, largest excess %.6g J); "
            "%s\n", e->first_created_j, e->first_step, e->first_time_s, e->first_limit_j,
            e->above_steps, e->max_excess_j,
            !finished ? "before the run stopped"
            : a->cfg.accept_energy_growth
                ? "accepted because coupler.json sets accept_energy_growth"
                : "exit status 3 (coupler.json \"accept_energy_growth\": true accepts it with "
                  "exit status 0)");
}

/* The end of the summary: how far the results can be trusted; the verdict is the last line.
 * Returns 1 when the results are reliable; *energy_ok: the energy guard did not fire;
 * *impulse_ok: the impulse guard did not. */
static int print_status(app *a, int *energy_ok, int *impulse_ok)
{
    const cpl_timing *t = cpl_loop_timing(a->loop);
    const cpl_loop_settings *s = &a->cfg.loop;
    const double dt_min = cpl_loop_settings_dt_min(s);
    FILE *o = a->progress.out;
    if (t->rejected_attempts > 0)
        fprintf(o, "coupler: step control: %ld steps needed a smaller dt (%ld tries rejected and "
                "repeated, %ld of them early as converging too slowly), smallest dt %.3g s "
                "(nominal %.3g s, dt_min %.3g s)\n", t->reduced_steps, t->rejected_attempts,
                t->slow_rejections, t->min_dt_s, s->dt_s, dt_min);
    else
        fprintf(o, "coupler: step control: no step rejected, no dt reduced (nominal %.3g s, "
                "dt_min %.3g s)\n", s->dt_s, dt_min);
    const cpl_energy *e = cpl_loop_energy(a->loop);
    *energy_ok = e->first_step < 0;
    *impulse_ok = !cpl_loop_uses_jacobian(a->loop) || !cpl_impulse_fired(cpl_loop_impulse(a->loop));
    print_energy(a);
    print_impulse(a);
    int reliable = 1;
    /* a weak run's verdict line too (scripts/report.py reads it): reliable as far as the
     * guards can tell, the residual being what the scheme leaves */
    if (s->scheme == CPL_SCHEME_WEAK)
        fprintf(o, "coupler: %sweak coupling, one exchange per step: the interface "
                "residual is not iterated away (it is recorded in /steps/residual)%s\n",
                *energy_ok && *impulse_ok ? "results are reliable: " : "results: ",
                *energy_ok && *impulse_ok ? "; no guard fired" : "");
    if (s->scheme == CPL_SCHEME_STRONG && t->unconverged_steps == 0) {
        /* the tests other than eq. (35)'s velocity half that may have decided a step */
        char other[400] = "";
        const int dv = s->relaxed == CPL_RELAXED_DISPLACEMENT_VELOCITY;
        const int by_work = dv && s->work_tol > 0.0, by_estimate = dv && s->newton_estimate > 0.0;
        if (by_work && by_estimate)
            snprintf(other, sizeof other, " (velocities, or the step's interface work mismatch "
                     "within work_tolerance %.3g of the input energy: %ld of %ld steps by it, or "
                     "the error estimate of the structure's last answer after a contraction of "
                     "at most newton_estimate %.3g: %ld steps by it)", s->work_tol,
                     t->work_test_steps, t->steps, s->newton_estimate, t->estimate_steps);
        else if (by_work)
            snprintf(other, sizeof other, " (velocities, or the step's interface work mismatch "
                     "within work_tolerance %.3g of the input energy: %ld of %ld steps by the "
                     "latter)", s->work_tol, t->work_test_steps, t->steps);
        else if (by_estimate)
            snprintf(other, sizeof other, " (velocities, or the error estimate of the "
                     "structure's last answer after a contraction of at most newton_estimate "
                     "%.3g: %ld of %ld steps by the latter)", s->newton_estimate,
                     t->estimate_steps, t->steps);
        fprintf(o, "coupler: %severy step converged to the tolerance %.3g%s\n",
                *energy_ok && *impulse_ok ? "results are reliable: " : "", s->tol_abs, other);
    } else if (s->scheme == CPL_SCHEME_STRONG) {
        /* every verdict that applies, the unconverged steps last */
        if (!*energy_ok) print_energy_verdict(a, 1);
        if (!*impulse_ok) print_impulse_verdict(a);
        reliable = 0;
        char why[256];
        if (dt_min < s->dt_s * (1.0 - 1e-9))
            snprintf(why, sizeof why, "even at the smallest step dt_min = %.3g s", dt_min);
        else
            snprintf(why, sizeof why, "step rejection is off (step_control.dt_min = dt)");
        fprintf(o, "coupler: results are NOT reliable: %ld of %ld steps were accepted without "
                "converging (interface residual above the tolerance %.3g after %d iterations, "
                "%s); %s\n", t->unconverged_steps, t->steps, s->tol_abs, s->max_iterations, why,
                a->cfg.accept_unconverged
                    ? "accepted because coupler.json sets accept_unconverged"
                    : "exit status 3 (coupler.json \"accept_unconverged\": true accepts them "
                      "with exit status 0)");
    }
    if (!*energy_ok && reliable) print_energy_verdict(a, 1);
    if (!*impulse_ok && reliable) print_impulse_verdict(a);
    fflush(o);
    return reliable && *energy_ok && *impulse_ok;
}

/* Convergence options that the run's scheme or exchange leaves without effect are accepted
 * (a case may set them for the variants it is run in) but said, also with --quiet: a user
 * who set them expects them to act. */
static void warn_idle_options(app *a, int both_jacobian, int both_compliance)
{
    const cpl_loop_settings *s = &a->cfg.loop;
    const int strong = s->scheme == CPL_SCHEME_STRONG;
    const int force_residual = strong && s->relaxed == CPL_RELAXED_FORCE;
    const char *why_not = !strong ? "the weak scheme exchanges once per step, nothing converges"
                          : force_residual ? "relaxed_quantity \"force\" converges on the "
                                             "forces, eq. (36)"
                                           : NULL;
    if (s->work_tol > 0.0 && why_not)
        cpl_progress_message(&a->progress, "coupler: warning: %s: work_tolerance has no "
                             "effect: %s", a->config_path, why_not);
    const char *why_not_jacobian = why_not;
    if (!why_not_jacobian && !s->interface_jacobian)
        why_not_jacobian = "interface_jacobian is false";
    if (!why_not_jacobian && !both_jacobian)
        why_not_jacobian = "a participant lacks the capability 'jacobian'";
    if (s->interface_compliance) {
        const char *why = why_not_jacobian ? why_not_jacobian
                          : !both_compliance ? "a participant lacks the capability 'compliance'"
                                             : NULL;
        if (why)
            cpl_progress_message(&a->progress, "coupler: warning: %s: interface_compliance has "
                                 "no effect: the structure's compliance comes with the interface "
                                 "Jacobian's iteration, and %s", a->config_path, why);
    }
    if (!(s->newton_estimate > 0.0)) return;
    why_not = why_not_jacobian;
    if (why_not)
        cpl_progress_message(&a->progress, "coupler: warning: %s: newton_estimate has no "
                             "effect: it judges the structure's Newton step with the interface "
                             "Jacobian, and %s", a->config_path, why_not);
}

/* --check: coupler.json read and checked as a run would (the participants' capabilities
 * are not known: the warnings that need them assume both can linearise). */
static int check_config(app *a)
{
    nc_error err;
    nc_error_clear(&err);
    cpl_config_default(&a->cfg);
    if (cpl_config_load(&a->cfg, a->config_path, &err)) {
        fprintf(stderr, "coupler: error: %s\n", err.message);
        return 1;
    }
    cpl_progress_init(&a->progress, stdout, 0, 0, a->cfg.progress_interval_s,
                      a->cfg.loop.start_time_s, a->cfg.loop.end_time_s, a->cfg.loop.dt_s);
    warn_idle_options(a, 1, 1);
    printf("coupler: %s: valid (checked only, nothing run)\n", a->config_path);
    return 0;
}

int main(int argc, char **argv)
{
    app a;
    memset(&a, 0, sizeof a);
    if (parse_args(&a, argc, argv)) return 1;
    setvbuf(stdout, NULL, _IOLBF, 0);
    if (a.check_only) return check_config(&a);

    a.stop_signal = nc_signal_catch_stop();   /* a blocking wait returns on Ctrl-C */
    signal(SIGPIPE, SIG_IGN);

    nc_error err;
    nc_error_clear(&err);
    int rc = 1, history_open = 0;
    double *u0 = NULL, *v0 = NULL;
    cpl_failure failure;
    memset(&failure, 0, sizeof failure);
    cpl_run_status status = {.impulse_missed_share = NAN};
    cpl_config_default(&a.cfg);
    int tty = isatty(STDOUT_FILENO);
    cpl_progress_init(&a.progress, stdout, tty, a.quiet, 10.0, 0.0, 1.0, 1.0);
    a.watch = (cpl_progress_watch){NAN, NAN, NAN, NAN};
    if (a.progress_path && cpl_heartbeat_start(&a.heartbeat, a.progress_path, 1.0, &err)) {
        fprintf(stderr, "coupler: error: %s\n", err.message);
        return 1;
    }
    /* endpoints given on the command line are known even if coupler.json is bad */
    if (a.fem_ep_arg) snprintf(a.fem_ep, sizeof a.fem_ep, "%s", a.fem_ep_arg);
    if (a.dem_ep_arg) snprintf(a.dem_ep, sizeof a.dem_ep, "%s", a.dem_ep_arg);
    if (cpl_config_load(&a.cfg, a.config_path, &err)) {
        cpl_config_default(&a.cfg);   /* the defaults' timeouts for the shutdown below */
        goto fail;
    }
    cpl_progress_init(&a.progress, stdout, tty, a.quiet, a.cfg.progress_interval_s,
                      a.cfg.loop.start_time_s, a.cfg.loop.end_time_s, a.cfg.loop.dt_s);
    struct winsize ws;
    if (tty && ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0) a.progress.width = ws.ws_col;
    if (nc_file_make_dirs(a.output_dir, &err)) goto fail;
    if (a.resume && read_manifest(&a, &err)) goto fail;

    char *fem_ep = a.fem_ep, *dem_ep = a.dem_ep;
    /* start-up waits: each is bounded by the connect or reply timeout */
    const double t_connect = a.cfg.connect_timeout_s, t_reply = a.cfg.reply_timeout_s;
    int bad;
    const double t_files = a.endpoint_wait_s > 0.0 ? a.endpoint_wait_s : t_connect;
    cpl_heartbeat_wait_begin(a.heartbeat, "fem", t_files);
    bad = resolve_endpoint(&a, &a.cfg.fem, a.fem_ep_arg, a.fem_ep_file_arg, "fem", fem_ep,
                           sizeof a.fem_ep, &err);
    cpl_heartbeat_wait_begin(a.heartbeat, "dem", t_files);
    bad = bad || resolve_endpoint(&a, &a.cfg.dem, a.dem_ep_arg, a.dem_ep_file_arg, "dem",
                                  dem_ep, sizeof a.dem_ep, &err);
    cpl_heartbeat_wait_begin(a.heartbeat, "fem", t_connect + t_reply);
    bad = bad || cpl_remote_open(&a.fem, CPL_REMOTE_FEM, fem_ep, t_connect, t_reply, &err);
    cpl_heartbeat_wait_end(a.heartbeat);
    if (bad) goto fail;
    a.fem_open = 1;
    cpl_heartbeat_wait_begin(a.heartbeat, "dem", t_connect + t_reply);
    bad = cpl_remote_open(&a.dem, CPL_REMOTE_DEM, dem_ep, t_connect, t_reply, &err);
    cpl_heartbeat_wait_end(a.heartbeat);
    if (bad) goto fail;
    a.dem_open = 1;
    if (!a.quiet)
        cpl_progress_message(&a.progress, "coupler: fem = %s (%s, protocol %d), dem = %s (%s, "
                             "protocol %d)", a.fem.peer_program, fem_ep, a.fem.version,
                             a.dem.peer_program, dem_ep, a.dem.version);
    /* strong coupling repeats steps: a participant that cannot restore would silently give
     * an unconverged answer (the loop also verifies it on the first step) */
    if (a.cfg.loop.scheme == CPL_SCHEME_STRONG)
        for (int k = 0; k < 2; k++) {
            const cpl_remote *r = k ? &a.dem : &a.fem;
            if (!proto_has_capability(r->capabilities, "restore")) {
                nc_error_set(&err, 1, "%s (%s) does not announce the capability 'restore' "
                             "(capabilities: '%s'); strong coupling repeats steps and needs it: "
                             "use \"scheme\": \"weak\" with this participant", r->name,
                             r->peer_program, r->capabilities);
                goto fail;
            }
        }

    /* checkpoints need both participants (protocol/README.md §3.3) */
    if (a.cfg.loop.checkpoint_interval_s > 0.0 || a.resume)
        for (int k = 0; k < 2; k++) {
            const cpl_remote *r = k ? &a.dem : &a.fem;
            if (cpl_remote_can_checkpoint(r)) continue;
            if (a.resume) {
                nc_error_set(&err, 1, "%s (%s) does not announce the capability 'checkpoint' "
                             "(protocol %d, capabilities: '%s'): cannot resume", r->name,
                             r->peer_program, r->version, r->capabilities);
                goto fail;
            }
            cpl_progress_message(&a.progress, "coupler: warning: checkpoints off: %s (%s) does "
                                 "not announce the capability 'checkpoint' (protocol %d, "
                                 "capabilities: '%s'); checkpoint.interval_s is ignored",
                                 r->name, r->peer_program, r->version, r->capabilities);
            break;
        }

    /* conforming interface (section 4.4): the FEM's interface mesh is the DEM's wall */
    cpl_heartbeat_wait_begin(a.heartbeat, "fem", t_reply);
    bad = cpl_remote_interface_fem(&a.fem, &a.mesh, &u0, &v0, &err);
    cpl_heartbeat_wait_begin(a.heartbeat, "dem", t_reply);
    bad = bad || cpl_remote_interface_dem(&a.dem, &a.mesh, &err);
    cpl_heartbeat_wait_end(a.heartbeat);
    if (bad) goto fail;
    if (!a.quiet)
        cpl_progress_message(&a.progress, "coupler: interface of %zu nodes, %zu elements; %s "
                             "scheme, dt %g s, end %g s", a.mesh.n_nodes, a.mesh.n_elements,
                             a.cfg.loop.scheme == CPL_SCHEME_STRONG ? "strong" : "weak",
                             a.cfg.loop.dt_s, a.cfg.loop.end_time_s);
    if (cpl_loop_create(&a.loop, &a.cfg.loop, a.mesh.n_nodes, u0, v0, &err)) goto fail;
    if (a.resume) {
        if (load_checkpoint(&a, &err) ||
            cpl_history_resume(&a.history, a.output_dir, &a.cfg.loop, a.cfg.write_iterations,
                               &err))
            goto fail;
        /* also with --quiet: a result continued from a checkpoint says so */
        cpl_progress_message(&a.progress, "coupler: resuming from checkpoint %s (step %ld, "
                             "t = %.6g s)", a.ckpt_name, cpl_loop_step(a.loop),
                             cpl_loop_time(a.loop));
    } else if (cpl_history_open(&a.history, a.output_dir, &a.cfg.loop, a.cfg.write_iterations,
                                &err)) {
        goto fail;
    }
    history_open = 1;

    cpl_participant fem = watch_participant(&a, &a.fem_w, &a.fem);
    cpl_participant dem = watch_participant(&a, &a.dem_w, &a.dem);
    beat(&a, "running");
    if (!a.quiet)
        cpl_progress_message(&a.progress, "coupler: interface Jacobian %s",
                             !a.cfg.loop.interface_jacobian ? "off (interface_jacobian false)"
                             : !cpl_loop_settings_jacobian_applies(&a.cfg.loop)
                                 ? "not used with relaxed_quantity \"force\" (it needs the "
                                   "displacement-velocity residual)"
                             : fem.can_jacobian && dem.can_jacobian
                                 ? "on: the FEM solves with the DEM's contact linearisation"
                                 : "not available (a participant lacks the capability "
                                   "'jacobian'): plain exchange");
    if (!a.quiet && a.cfg.loop.interface_compliance && fem.can_jacobian && dem.can_jacobian &&
        fem.can_compliance && dem.can_compliance && cpl_loop_settings_jacobian_applies(&a.cfg.loop))
        cpl_progress_message(&a.progress, "coupler: interface compliance on: the DEM solves "
                             "its steps with the structure's compliance at the contact nodes");
    warn_idle_options(&a, fem.can_jacobian && dem.can_jacobian,
                      fem.can_compliance && dem.can_compliance);
    cpl_observer obs = {&a, observe_iteration, observe_step, observe_reject, observe_checkpoint};
    if (cpl_loop_run(a.loop, &fem, &dem, &obs, a.stop_signal, &failure, &err)) {
        /* say which signal; one that interrupted a wait shows up as a transport error of
         * that participant, which is not its fault */
        if (*a.stop_signal) {
            const char *name = *a.stop_signal == SIGINT ? "SIGINT" : "SIGTERM";
            if (err.code == CPL_ERR_INTERRUPTED) {
                char where[NC_ERROR_MESSAGE_MAX];
                const char *at = strstr(err.message, " at step");
                snprintf(where, sizeof where, "%s", at ? at : "");
                nc_error_set(&err, CPL_ERR_INTERRUPTED, "interrupted by %s%s", name, where);
            } else {
                char reason[NC_ERROR_MESSAGE_MAX];
                snprintf(reason, sizeof reason, "%s", err.message);
                nc_error_set(&err, CPL_ERR_INTERRUPTED, "interrupted by %s (%s)", name, reason);
            }
            failure.participant = NULL;
        }
        goto fail;
    }
    /* the rows still in memory reach coupling.h5 before the participants are told to go
     * (which may take seconds), and a full disk fails the run */
    if (cpl_history_flush(&a.history, &err)) goto fail;
    beat(&a, "finishing");   /* first: run_case.sh then shows the final status line */
    cpl_progress_finish(&a.progress);
    rc = shutdown_all(&a, NULL) ? 1 : 0;
    print_timing(&a);
    status.finished = 1;
    int energy_ok = 1, impulse_ok = 1;
    status.reliable = print_status(&a, &energy_ok, &impulse_ok);
    status.energy_growth = !energy_ok;
    status.impulse_loss = !impulse_ok;
    if (cpl_loop_uses_jacobian(a.loop))
        status.impulse_missed_share = cpl_impulse_missed_share(cpl_loop_impulse(a.loop));
    if (rc == 0 && ((cpl_loop_timing(a.loop)->unconverged_steps > 0 && !a.cfg.accept_unconverged) ||
                    (!energy_ok && !a.cfg.accept_energy_growth) ||
                    (!impulse_ok && !a.cfg.accept_impulse_loss)))
        rc = EXIT_UNRELIABLE;
    goto done;

fail:
    beat(&a, "stopping");
    cpl_progress_finish(&a.progress);
    /* a signal during start-up (connecting, interface) is the user's stop too; the loop's
     * own failures were reworded above */
    if (*a.stop_signal && !strstr(err.message, "interrupted by SIG")) {
        char reason[NC_ERROR_MESSAGE_MAX];
        snprintf(reason, sizeof reason, "%s", err.message);
        nc_error_set(&err, CPL_ERR_INTERRUPTED, "interrupted by %s (%s)",
                     *a.stop_signal == SIGINT ? "SIGINT" : "SIGTERM", reason);
        failure.participant = NULL;
    }
    fprintf(stderr, "coupler: error: %s\n", err.message);
    if (history_open) {
        nc_error history_err;
        if (cpl_history_flush(&a.history, &history_err))
            fprintf(stderr, "coupler: warning: %s\n", history_err.message);
    }
    shutdown_all(&a, failure.participant);
    if (a.loop) {
        print_timing(&a);
        /* a run that stopped says whether the energy guard had fired before, in the summary
         * and in coupling.h5 (energy_growth) */
        if (cpl_loop_energy(a.loop)->first_step >= 0) {
            status.energy_growth = 1;
            print_energy_verdict(&a, 0);
        }
    }
    rc = *a.stop_signal == SIGINT ? 130 : *a.stop_signal == SIGTERM ? 143 : 1;
    /* stopped by its own energy guard: the results so far are written and not reliable */
    if (rc == 1 && err.code == CPL_ERR_ENERGY_GROWTH) rc = EXIT_UNRELIABLE;

done:
    status.accept_unconverged = a.cfg.accept_unconverged;
    status.accept_energy_growth = a.cfg.accept_energy_growth;
    status.accept_impulse_loss = a.cfg.accept_impulse_loss;
    if (history_open)
        cpl_history_close(&a.history, a.loop ? cpl_loop_timing(a.loop) : NULL,
                          a.loop ? cpl_loop_energy(a.loop) : NULL, &status);
    if (a.fem_open) cpl_remote_close(&a.fem);
    if (a.dem_open) cpl_remote_close(&a.dem);
    cpl_heartbeat_stop(a.heartbeat);
    cpl_loop_free(a.loop);
    cpl_mesh_free(&a.mesh);
    free(u0);
    free(v0);
    return rc;
}
