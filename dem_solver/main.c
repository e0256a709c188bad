/* dem_solver — command line program: a standalone DEM run with rigid walls, or a coupling
 * participant serving the coupler over the netcouple protocol (--endpoint).
 *
 *   dem_solver dem.json --output DIR
 *   dem_solver dem.json --endpoint EP --output DIR [--endpoint-file FILE] [--idle-timeout S]
 *
 * Exit codes: 0 success, 1 error (message on stderr), 2 usage, 130 interrupted (SIGINT/SIGTERM;
 * the results written so far are complete and readable).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem_config.h"
#include "dem_output.h"
#include "dem_sim.h"
#include "nc_file.h"
#include "nc_clock.h"
#include "nc_signal.h"
#include "proto.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: dem_solver dem.json --output DIR [--endpoint EP] [--endpoint-file FILE]\n"
            "                  [--idle-timeout SECONDS]\n"
            "  without --endpoint: standalone run with rigid walls (planes, STL meshes) until\n"
            "  end_time_s; with --endpoint: coupling participant (role \"dem\") serving the\n"
            "  coupler; results in DIR/dem.h5 and DIR/dem.xdmf. See dem_solver/README.md.\n");
}

typedef struct options {
    const char *input, *output, *endpoint, *endpoint_file;
    double idle_timeout_s;
} options;

static int parse_args(int argc, char **argv, options *o)
{
    memset(o, 0, sizeof *o);
    o->idle_timeout_s = -1.0;
    for (int k = 1; k < argc; k++) {
        const char *a = argv[k];
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            usage(stdout);
            exit(0);
        }
        int has_value = k + 1 < argc;
        if (strcmp(a, "--output") == 0 && has_value) o->output = argv[++k];
        else if (strcmp(a, "--endpoint") == 0 && has_value) o->endpoint = argv[++k];
        else if (strcmp(a, "--endpoint-file") == 0 && has_value) o->endpoint_file = argv[++k];
        else if (strcmp(a, "--idle-timeout") == 0 && has_value) {
            char *end;
            o->idle_timeout_s = strtod(argv[++k], &end);
            if (*end || !(o->idle_timeout_s >= 0.0)) {
                fprintf(stderr, "dem_solver: --idle-timeout: expected seconds >= 0, got '%s'\n", argv[k]);
                return -1;
            }
        } else if (a[0] == '-') {
            fprintf(stderr, "dem_solver: unknown option or missing value: %s\n", a);
            return -1;
        } else if (!o->input) o->input = a;
        else {
            fprintf(stderr, "dem_solver: unexpected argument: %s\n", a);
            return -1;
        }
    }
    if (!o->input) {
        fprintf(stderr, "dem_solver: missing input file dem.json\n");
        return -1;
    }
    if (!o->output) {
        fprintf(stderr, "dem_solver: missing --output DIR\n");
        return -1;
    }
    return 0;
}

/* Runs until end_time_s, or until *stop is set (returns 1 then, after writing the state). */
static int run_standalone(dem_sim *s, dem_output *out, const volatile sig_atomic_t *stop,
                          nc_error *err)
{
    double dt = s->model.prm.dt_s, end = s->model.prm.end_time_s, interval = s->model.prm.output_interval_s;
    long steps = (long)ceil(end / dt - 1e-9);
    printf("dem_solver: %zu spheres in %zu bodies, dt = %.3e s (critical %.3e s), %ld steps\n",
           s->model.sph.n, s->model.bod.n, dt, dem_sim_critical_dt(s), steps);
    if (dem_output_write(out, s, NULL, err)) return -1;
    double next_out = interval;
    double t0 = nc_clock_now_s();
    for (long k = 0; k < steps; k++) {
        if (*stop) {
            if (dem_output_write(out, s, NULL, err)) return -1;
            fprintf(stderr, "dem_solver: interrupted at t = %g s; results so far are in %s\n",
                    s->time_s, out->dir);
            return 1;
        }
        if (dem_sim_step(s, dt, err)) return nc_error_prefix(err, "step %ld (t = %g s)", k, s->time_s);
        if (s->time_s >= next_out - 0.5 * dt || k == steps - 1) {
            if (dem_output_write(out, s, NULL, err)) return -1;
            while (next_out <= s->time_s + 0.5 * dt) next_out += interval > 0.0 ? interval : dt;
        }
    }
    double wall = nc_clock_now_s() - t0;
    printf("dem_solver: done, t = %g s, %ld steps in %.2f s (%.3g particle-steps/s), %zu contacts\n",
           s->time_s, steps, wall, wall > 0 ? (double)steps * (double)s->model.sph.n / wall : 0.0,
           s->contact.list.n);
    return 0;
}

/* One command of the coupler; returns 0 to keep serving, 1 after SHUTDOWN. A failed command
 * gets an error reply (*failed is set) and serving continues. */
typedef struct coupled_state {
    double *force;          /* 3 per node: last time-averaged nodal force */
    size_t force_cap;
    int step_begun;
    double next_out;
    int failed;
} coupled_state;

static int handle(dem_sim *s, dem_output *out, proto_participant *p, const proto_message *cmd,
                  proto_message *reply, coupled_state *cs, nc_error *err)
{
    nc_error cmd_err;
    nc_error_clear(&cmd_err);
    proto_message_init(reply, cmd->type);
    int rc = 0, shutdown = 0;
    switch (cmd->type) {
    case PROTO_MSG_INTERFACE: {
        const int32_t *ids, *elements;
        const double *coords;
        size_t n, m;
        if (proto_message_get_i32(cmd, "node_ids", 0, 0, &ids, &n, &cmd_err) ||
            proto_message_get_f64(cmd, "coordinates", n, 3, &coords, NULL, &cmd_err) ||
            proto_message_get_i32(cmd, "elements", 0, 2, &elements, &m, &cmd_err) ||
            dem_sim_set_interface(s, n, ids, coords, m, elements, &cmd_err)) {
            rc = -1;
            break;
        }
        if ((size_t)cs->force_cap < 3 * n) {
            free(cs->force);
            cs->force = calloc(3 * n, sizeof *cs->force);
            cs->force_cap = cs->force ? 3 * n : 0;
            if (!cs->force) {
                rc = nc_error_set(&cmd_err, 1, "dem: out of memory");
                break;
            }
        }
        memset(cs->force, 0, 3 * n * sizeof *cs->force);
        printf("dem_solver: interface with %zu nodes and %zu elements\n", n, m);
        if (out->n_out == 0) rc = dem_output_write(out, s, cs->force, &cmd_err);
        break;
    }
    case PROTO_MSG_BEGIN_STEP:
        rc = dem_sim_begin_step(s, &cmd_err);
        cs->step_begun = rc == 0;
        break;
    case PROTO_MSG_SOLVE: {
        if (!s->model.net.active) {
            rc = nc_error_set(&cmd_err, 1, "dem: SOLVE before INTERFACE");
            break;
        }
        size_t n = s->model.net.n_nodes;
        const double *disp, *vel;
        if (proto_message_get_f64(cmd, "displacement", n, 3, &disp, NULL, &cmd_err) ||
            proto_message_get_f64(cmd, "velocity", n, 3, &vel, NULL, &cmd_err)) {
            rc = -1;
            break;
        }
        if (cmd->iteration > 1) {
            if (dem_sim_restore(s, &cmd_err)) { rc = -1; break; }
        } else if (!cs->step_begun) {
            if (dem_sim_begin_step(s, &cmd_err)) { rc = -1; break; }
            cs->step_begun = 1;
        }
        dem_coupled_info info;
        if (dem_sim_solve_coupled(s, cmd->dt_s, disp, vel, cs->force, &info, &cmd_err)) {
            nc_error_prefix(&cmd_err, "step %ld iteration %d", cmd->step, cmd->iteration);
            rc = -1;
            break;
        }
        if (proto_message_add_f64(reply, "force", cs->force, n, 3, &cmd_err) ||
            proto_message_set_value(reply, "near_interface", info.near_interface, &cmd_err) ||
            proto_message_set_value(reply, "min_gap_m", info.min_gap_m, &cmd_err) ||
            proto_message_set_value(reply, "contacts", (double)info.contacts, &cmd_err) ||
            proto_message_set_value(reply, "substeps", (double)info.substeps, &cmd_err))
            rc = -1;
        break;
    }
    case PROTO_MSG_ACCEPT_STEP:
        cs->step_begun = 0;
        if (s->time_s >= cs->next_out - 1e-12) {
            rc = dem_output_write(out, s, cs->force, &cmd_err);
            double interval = s->model.prm.output_interval_s;
            if (interval > 0.0)
                while (cs->next_out <= s->time_s + 1e-12) cs->next_out += interval;
            else cs->next_out = s->time_s;
        }
        break;
    case PROTO_MSG_SHUTDOWN:
        shutdown = 1;
        break;
    default:
        rc = nc_error_set(&cmd_err, 1, "dem: command '%s' is not supported",
                          proto_type_name(cmd->type));
        break;
    }
    if (rc) {
        cs->failed = 1;
        fprintf(stderr, "dem_solver: %s failed: %s\n", proto_type_name(cmd->type), cmd_err.message);
        if (proto_participant_reply_error(p, cmd_err.message, err)) return -1;
        return 0;
    }
    if (proto_participant_reply(p, reply, err)) return -1;
    return shutdown;
}

static int run_coupled(dem_sim *s, dem_output *out, const options *o,
                       const volatile sig_atomic_t *stop, nc_error *err)
{
    if (!(s->model.net.youngs_modulus_pa > 0.0))
        return nc_error_set(err, 1, "%s: net_wall: missing (the coupled mode needs the net wall "
                                    "material: youngs_modulus_pa, poisson_ratio, friction)",
                            s->model.source);
    proto_options popt;
    proto_options_default(&popt);
    if (o->idle_timeout_s >= 0.0) popt.idle_timeout_ms = (int)(o->idle_timeout_s * 1000.0);
    proto_participant *p;
    if (proto_participant_open(&p, o->endpoint, "dem", "netcouple dem_solver", "restore", &popt, err))
        return -1;
    if (o->endpoint_file && nc_file_write_line(o->endpoint_file, proto_participant_endpoint(p), err)) {
        proto_participant_close(p);
        return -1;
    }
    printf("dem_solver: %zu spheres, dt = %.3e s, serving %s\n", s->model.sph.n, s->model.prm.dt_s,
           proto_participant_endpoint(p));
    fflush(stdout);
    proto_message cmd, reply;
    memset(&cmd, 0, sizeof cmd);
    memset(&reply, 0, sizeof reply);
    coupled_state cs;
    memset(&cs, 0, sizeof cs);
    cs.next_out = s->model.prm.output_interval_s;
    int rc = 0;
    for (;;) {
        if (*stop) {
            fprintf(stderr, "dem_solver: interrupted at t = %g s\n", s->time_s);
            rc = 130;
            break;
        }
        if (proto_participant_receive(p, &cmd, err)) {
            if (err->code == PROTO_ERR_IDLE) {
                nc_error_prefix(err, "no command from the coupler (idle timeout)");
                rc = -1;
                break;
            }
            if (err->code == PROTO_ERR_DECODE || err->code == PROTO_ERR_VERSION) {
                fprintf(stderr, "dem_solver: bad command: %s\n", err->message);
                continue; /* an error reply was sent */
            }
            if (*stop) continue; /* a signal interrupted the wait */
            rc = -1;
            break;
        }
        int h = handle(s, out, p, &cmd, &reply, &cs, err);
        if (h < 0) {
            rc = -1;
            break;
        }
        if (h == 1) {
            rc = cs.failed ? 1 : 0;
            if (cs.failed) nc_error_set(err, 1, "a command failed during the run (see above)");
            break;
        }
    }
    proto_message_free(&cmd);
    proto_message_free(&reply);
    proto_participant_close(p);
    free(cs.force);
    return rc;
}

int main(int argc, char **argv)
{
    options o;
    if (parse_args(argc, argv, &o)) {
        usage(stderr);
        return 2;
    }
    const volatile sig_atomic_t *stop = nc_signal_catch_stop();

    nc_error err;
    nc_error_clear(&err);
    dem_sim s;
    dem_sim_init(&s);
    dem_output out;
    memset(&out, 0, sizeof out);
    out.h5.file = H5I_INVALID_HID;
    int rc = 0;
    if (dem_config_load(&s, o.input, &err) || dem_sim_prepare(&s, &err) ||
        nc_file_make_dirs(o.output, &err) || dem_output_open(&out, &s, o.output, &err)) {
        rc = -1;
    } else {
        rc = o.endpoint ? run_coupled(&s, &out, &o, stop, &err)
                        : run_standalone(&s, &out, stop, &err);
    }
    dem_output_close(&out);
    dem_sim_free(&s);
    if (rc < 0) {
        fprintf(stderr, "dem_solver: %s\n", err.message);
        return 1;
    }
    if (rc == 1 && err.message[0]) fprintf(stderr, "dem_solver: %s\n", err.message);
    return rc == 1 ? (*stop ? 130 : 1) : rc;
}
