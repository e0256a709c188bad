/* dem_solver — command line program: a standalone DEM run with rigid walls, or a coupling
 * participant serving the coupler over the netcouple protocol (--endpoint).
 *
 *   dem_solver dem.json --output DIR
 *   dem_solver dem.json --endpoint EP --output DIR [--endpoint-file FILE] [--idle-timeout S]
 *   dem_solver dem.json --check [--endpoint EP]
 *
 * Exit codes: 0 success, 1 error (message on stderr), 2 usage, 130 interrupted (SIGINT/SIGTERM;
 * the results written so far are complete and readable).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem_config.h"
#include "dem_contact_hertz.h"
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
            "       dem_solver dem.json --check [--endpoint EP]\n"
            "  without --endpoint: standalone run with rigid walls (planes, STL meshes) until\n"
            "  end_time_s; with --endpoint: coupling participant (role \"dem\") serving the\n"
            "  coupler; results in DIR/dem.h5 with DIR/particles.xdmf (the particles) and,\n"
            "  coupled, DIR/dem_net.xdmf (the net wall). --check reads and checks dem.json\n"
            "  (and the STL files it names; with --endpoint also what the coupled mode\n"
            "  needs), prints the summary and its warnings and runs nothing: exit 0 when it\n"
            "  is valid, 1 with the error. See dem_solver/README.md.\n");
}

typedef struct options {
    const char *input, *output, *endpoint, *endpoint_file;
    double idle_timeout_s;
    int check_only;     /* --check: read and check the input, run nothing */
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
        if (strcmp(a, "--check") == 0) o->check_only = 1;
        else if (strcmp(a, "--output") == 0 && has_value) o->output = argv[++k];
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
    if (!o->output && !o->check_only) {
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
            if (dem_output_write(out, s, NULL, err) || dem_output_flush(out, err)) return -1;
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
    if (dem_output_flush(out, err)) return -1;   /* the rows still in memory, before "done" */
    double wall = nc_clock_now_s() - t0;
    printf("dem_solver: done, t = %.9g s, %ld steps in %.2f s (%.3g particle-steps/s), %zu contacts\n",
           s->time_s, steps, wall, wall > 0 ? (double)steps * (double)s->model.sph.n / wall : 0.0,
           s->contact.list.n);
    return 0;
}

/* The impact contact of a body on the wall it will hit (the net wall when configured, else a
 * rigid flat wall): rigid wall, so m* = m and R* = R (the body's largest sphere), at the speed
 * v (at least 1 m/s, as for the automatic dt). Hertz: t_c = 2.87 (m*² / (R* E*² v))^(1/5)
 * with E* of the sphere's material and the wall's (E* = E / (1 − ν²) of the sphere alone for a
 * rigid one); linear law: half an undamped period π sqrt(m / kn). */
static double impact_contact_time_s(const dem_sim *s, size_t b, double speed)
{
    const dem_model *m = &s->model;
    int32_t first = m->bod.first_sphere[b];
    double r = 0.0;
    for (int32_t q = first; q < first + m->bod.n_spheres[b]; q++) r = fmax(r, m->sph.radius[q]);
    double mass = m->bod.mass[b];
    if (m->prm.law == DEM_LAW_LINEAR) return M_PI * sqrt(mass / m->prm.linear_kn_n_per_m);
    const dem_material *mat = &m->materials[m->sph.material[first]];
    double compliance = (1.0 - mat->poisson_ratio * mat->poisson_ratio) / mat->youngs_modulus_pa;
    if (m->net.youngs_modulus_pa > 0.0)
        compliance += (1.0 - m->net.poisson_ratio * m->net.poisson_ratio) / m->net.youngs_modulus_pa;
    double e_star = 1.0 / compliance, v = fmax(1.0, speed);
    return 2.87 * pow(mass * mass / (r * e_star * e_star * v), 0.2);
}

/* The start-up summary on `out` (one block): what dem.json built, the heaviest-hitting bodies
 * with mass, size, speed, kinetic energy and estimated contact time, and the DEM step; a user
 * step that resolves a contact with fewer than 20 steps is a warning on `warn`. */
static void print_summary(const dem_sim *s, const char *input, FILE *out, FILE *warn)
{
    const dem_model *m = &s->model;
    enum { SHOWN = 5 };
    size_t order[SHOWN], n_shown = 0;
    double total_mass = 0.0, total_ke = 0.0;
    for (size_t b = 0; b < m->bod.n; b++) {
        const double *v = m->bod.vel + 3 * b;
        double ke = 0.5 * m->bod.mass[b] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        total_mass += m->bod.mass[b];
        total_ke += ke;
        /* keep the SHOWN bodies of largest kinetic energy (then mass), in that order */
        size_t at = n_shown;
        while (at > 0) {
            size_t o = order[at - 1];
            const double *w = m->bod.vel + 3 * o;
            double ko = 0.5 * m->bod.mass[o] * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            if (ke > ko || (ke == ko && m->bod.mass[b] > m->bod.mass[o])) at--;
            else break;
        }
        if (at >= SHOWN) continue;
        if (n_shown < SHOWN) n_shown++;
        for (size_t k = n_shown - 1; k > at; k--) order[k] = order[k - 1];
        order[at] = b;
    }
    fprintf(out, "dem_solver: %s: %zu bod%s (%zu sphere%s), total mass %.6g kg, kinetic energy "
                 "%.6g J\n", input, m->bod.n, m->bod.n == 1 ? "y" : "ies", m->sph.n,
            m->sph.n == 1 ? "" : "s", total_mass, total_ke);
    const char *wall = m->net.youngs_modulus_pa > 0.0 ? "the net wall" : "a rigid wall";
    double tc_min = INFINITY;
    size_t b_min = 0;
    for (size_t k = 0; k < n_shown; k++) {
        size_t b = order[k];
        const double *v = m->bod.vel + 3 * b;
        double speed = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        int32_t first = m->bod.first_sphere[b], ns = m->bod.n_spheres[b];
        double r = 0.0;
        for (int32_t q = first; q < first + ns; q++) r = fmax(r, m->sph.radius[q]);
        double tc = impact_contact_time_s(s, b, speed);
        if (tc < tc_min) {
            tc_min = tc;
            b_min = b;
        }
        if (ns == 1)
            fprintf(out, "  body %zu: sphere radius %.6g m, ", b, r);
        else
            fprintf(out, "  body %zu: cluster of %d spheres (largest radius %.6g m), ", b, ns, r);
        fprintf(out, "mass %.6g kg, material %s, speed %.6g m/s, kinetic energy %.6g J, "
                     "contact time on %s ~%.3g s%s\n",
                m->bod.mass[b], m->materials[m->sph.material[first]].name, speed,
                0.5 * m->bod.mass[b] * speed * speed, wall, tc, speed < 1.0 ? " (at 1 m/s)" : "");
    }
    if (m->bod.n > n_shown)
        fprintf(out, "  ... and %zu more bodies (the %zu of largest kinetic energy shown)\n",
                m->bod.n - n_shown, n_shown);
    double dt = m->prm.dt_s;
    fprintf(out, "  DEM step %.3e s (%s; critical step %.3e s)", dt,
            m->prm.dt_auto ? "auto" : "dt_s", dem_sim_critical_dt(s));
    if (isfinite(tc_min)) fprintf(out, ", %.0f steps per contact of body %zu", tc_min / dt, b_min);
    fputc('\n', out);
    /* a rule of thumb for accuracy, not a stability limit: about ten coupling steps per
     * contact resolve its force history */
    if (isfinite(tc_min) && m->net.youngs_modulus_pa > 0.0)
        fprintf(out, "  coupling dt: %.3g s or less suggested (a tenth of the shortest contact "
                     "with the net, body %zu)\n", 0.1 * tc_min, b_min);
    if (!m->prm.dt_auto && isfinite(tc_min) && tc_min / dt < 20.0)
        fprintf(warn, "warning: %s: dt_s: %g s resolves the contact of body %zu "
                      "(~%.3g s) with only %.0f steps; 20 or more (\"auto\" gives >= 40) are "
                      "needed for an accurate rebound\n", input, dt, b_min, tc_min, tc_min / dt);
    fflush(out);
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
    dem_config_options copt = {.warnings = stderr};
    int built = dem_config_load_opt(&s, o.input, &copt, &err) == 0 && dem_sim_prepare(&s, &err) == 0;
    if (built) print_summary(&s, o.input, stdout, stderr);
    if (built && o.check_only && o.endpoint && dem_participant_check_input(&s, &err)) {
        rc = -1;
    } else if (built && o.check_only) {
        printf("dem_solver: %s: valid (checked only, nothing run)\n", o.input);
    } else if (!built || nc_file_make_dirs(o.output, &err) || dem_output_open(&out, &s, o.output, &err)) {
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
