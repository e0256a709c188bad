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
#include "dem_participant.h"
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

/* Runs until end_time_s, or until *stop is set (returns 1 then, after writing the state).
 * Output falls on exact multiples of output_interval_s and the run ends exactly at
 * end_time_s: the step that would pass one of these times is shortened to meet it (a
 * shorter step is never less stable), and the clock is set to that time, so repeated sums
 * of dt do not drift. */
static int run_standalone(dem_sim *s, dem_output *out, const volatile sig_atomic_t *stop,
                          nc_error *err)
{
    double dt = s->model.prm.dt_s, end = s->model.prm.end_time_s, interval = s->model.prm.output_interval_s;
    long estimate = (long)ceil(end / dt - 1e-9);
    printf("dem_solver: %zu spheres in %zu bodies, dt = %.3e s (critical %.3e s), %ld steps\n",
           s->model.sph.n, s->model.bod.n, dt, dem_sim_critical_dt(s), estimate);
    if (dem_output_write(out, s, NULL, err)) return -1;
    double t0 = nc_clock_now_s();
    long steps = 0, next_out = 1;
    while (s->time_s < end) {
        if (*stop) {
            if (dem_output_write(out, s, NULL, err)) return -1;
            fprintf(stderr, "dem_solver: interrupted at t = %g s; results so far are in %s\n",
                    s->time_s, out->dir);
            return 1;
        }
        double target = interval > 0.0 ? fmin((double)next_out * interval, end) : end;
        double h = dt;
        int reaches = 0;
        if (s->time_s + dt >= target - 1e-6 * dt) {
            h = target - s->time_s;
            reaches = 1;
        }
        if (dem_sim_step(s, h, err)) return nc_error_prefix(err, "step %ld (t = %g s)", steps, s->time_s);
        steps++;
        if (reaches) s->time_s = target;
        if (reaches || interval <= 0.0) {
            if (dem_output_write(out, s, NULL, err)) return -1;
            if (reaches && interval > 0.0 && target < end) next_out++;
        }
    }
    double wall = nc_clock_now_s() - t0;
    printf("dem_solver: done, t = %.9g s, %ld steps in %.2f s (%.3g particle-steps/s), %zu contacts\n",
           s->time_s, steps, wall, wall > 0 ? (double)steps * (double)s->model.sph.n / wall : 0.0,
           s->contact.list.n);
    return 0;
}

static int run_coupled(dem_sim *s, dem_output *out, const options *o,
                       const volatile sig_atomic_t *stop, nc_error *err)
{
    dem_participant_options po = {
        .endpoint = o->endpoint, .endpoint_file = o->endpoint_file,
        .idle_timeout_ms = o->idle_timeout_s >= 0.0 ? (int)(o->idle_timeout_s * 1000.0)
                                                    : PROTO_DEFAULT_IDLE_TIMEOUT_MS,
        .progress = stdout, .problems = stderr};
    return dem_participant_run(s, out, &po, stop, err);
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
