/* fem_solver — command-line program: the netcouple cable-net FEM, standalone or as the
 * "fem" participant of a coupled run.
 *
 *   fem_solver fem.json --output DIR
 *   fem_solver fem.json --endpoint EP --output DIR [--endpoint-file FILE] [--idle-timeout S]
 *   fem_solver fem.json --check [--endpoint EP]
 *
 * SIGINT/SIGTERM stop the run after the current step; results so far are kept.
 * Exit codes: 0 success, 1 error (message on stderr), 2 usage, 3 finished but an axial force
 * exceeded its set's breaking_load_n with analysis.fail_on_overload (without it: a warning
 * only), 130 stopped by a signal.
 */
#include "fem_element.h"
#include "fem_input.h"
#include "fem_run.h"
#include "nc_clock.h"
#include "nc_file.h"
#include "nc_plausible.h"
#include "nc_signal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *f)
{
    fprintf(f,
            "usage: fem_solver INPUT.json --output DIR\n"
            "       fem_solver INPUT.json --endpoint EP --output DIR [--endpoint-file FILE]\n"
            "                  [--idle-timeout SECONDS]\n"
            "       fem_solver INPUT.json --check [--endpoint EP]\n"
            "Standalone: runs the analysis of INPUT.json (static load steps or dynamics) and\n"
            "writes DIR/fem.h5 and DIR/fem.xdmf. With --endpoint it serves the netcouple\n"
            "protocol as participant \"fem\" (EP e.g. tcp://127.0.0.1:5555 or tcp://127.0.0.1:*).\n"
            "--check reads and checks INPUT.json (and the files it names), prints the\n"
            "summary and its warnings (with --endpoint: also those of a coupled run), and\n"
            "runs nothing: exit 0 when it is valid, 1 with the error.\n"
            "Input keys: fem_solver/README.md.\n");
}

/* The start-up summary on stdout (one block): the model's size and, per element set, its
 * section and what it carries (EA, the pretension force A·S_pre, the breaking load if given)
 * and its mass ρ A L, so a unit mistake shows before the run. */
static void print_summary(const fem_model *m, const char *input, FILE *out)
{
    double total_mass = 0.0;
    int fixed_nodes = 0;
    for (int i = 0; i < m->n_nodes; i++)
        fixed_nodes += m->fixed[3 * i] || m->fixed[3 * i + 1] || m->fixed[3 * i + 2];
    for (int e = 0; e < m->n_elements; e++) total_mass += m->rhoA[e] * m->L0[e];
    fprintf(out, "fem_solver: %s: %d nodes (%d supported), %d elements, %d element set%s, "
                 "net mass %.6g kg, %s analysis\n", input, m->n_nodes, fixed_nodes,
            m->n_elements, m->n_sets, m->n_sets == 1 ? "" : "s", total_mass,
            m->settings.type == FEM_STATIC ? "static" : "dynamic");
    for (int k = 0; k < m->n_sets; k++) {
        const fem_element_set *set = &m->sets[k];
        int count = 0;
        double length = 0.0;
        for (int e = 0; e < m->n_elements; e++)
            if (m->element_set[e] == k) {
                count++;
                length += m->L0[e];
            }
        double a = set->area_m2, force = set->prestress_pa * a;
        /* The element type; a set of type cable shows its behaviour (cable or truss). */
        const fem_element_ops *ops = fem_element_type(m->set_types ? m->set_types[k].type : 0);
        const char *kind = ops && m->set_types && m->set_types[k].type != FEM_TYPE_CABLE
                               ? ops->name
                               : set->behaviour == FEM_CABLE ? "cable" : "truss";
        fprintf(out, "  set %s (%s): %d elements, length %.6g m, E %.4g Pa, A %.4g m², "
                     "EA %.4g N, pretension %.4g N (%.4g Pa), mass %.6g kg",
                set->name, kind, count, length,
                set->youngs_modulus_pa, a, set->youngs_modulus_pa * a,
                force, set->prestress_pa, set->density_kg_m3 * a * length);
        if (set->breaking_load_n > 0.0)
            fprintf(out, ", breaking load %.4g N (pretension %.3g %% of it)", set->breaking_load_n,
                    100.0 * force / set->breaking_load_n);
        fputc('\n', out);
    }
    fflush(out);
}

/* A coupled run whose integrator has no numerical damping (γ = ½: Newmark's trapezoid,
 * generalized-α with rho_inf 1, Bossak 0) and takes the coupling force as the load at the
 * step's end: the DEM's step-averaged contact force then acts as a spring delayed by half a
 * step, a negative damper that nothing outweighs (docs/notes/rest_position.md). */
static void warn_undamped_coupling(const fem_model *m, const char *input)
{
    const fem_settings *s = &m->settings;
    if (s->type != FEM_DYNAMIC || s->coupling_load_constant) return;
    const double gamma = s->integrator == FEM_BOSSAK ? 0.5 - s->alpha_b
                       : s->integrator == FEM_GENERALIZED_ALPHA
                           ? 0.5 + (1.0 - s->rho_inf) / (1.0 + s->rho_inf)
                           : s->gamma;
    if (gamma > 0.5 + 1e-9) return;
    nc_warn(stderr, "%s: analysis: a coupled run with gamma 0.5 (no numerical damping) and the "
                    "coupling force as the load at the end of the step: the DEM's step-averaged "
                    "contact force then acts as a spring delayed by half a step and feeds energy "
                    "into the net (cases/steel_net with Newmark's trapezoid: 10 times its input "
                    "energy by 0.16 s); the cases use integrator \"bossak\" with alpha_b -0.3 (the "
                    "barrier cases -0.1 with the ropes' kappa damping; "
                    "docs/notes/rest_position.md)", input);
}

/* Progress of a settling that takes a while (the initial equilibrium of a large barrier takes
 * a minute and more): a line on stdout every SETTLE_REPORT_S from SETTLE_QUIET_S on, so a log
 * and a launcher see that the solver is working before it publishes its endpoint. */
enum { SETTLE_QUIET_S = 2, SETTLE_REPORT_S = 5 };
typedef struct settle_progress {
    const char *input;
    double t0_s, last_s;
} settle_progress;

static void settle_step(void *ctx, int step, double h_s, double move_m, int node)
{
    settle_progress *p = ctx;
    const double now = nc_clock_now_s();
    if (now - p->t0_s < SETTLE_QUIET_S || now - p->last_s < SETTLE_REPORT_S) return;
    p->last_s = now;
    printf("fem_solver: %s: settling in static equilibrium: pseudo-time step %d of %g s, "
           "largest move %.3g m (node %d), %.0f s so far\n", p->input, step, h_s, move_m, node,
           now - p->t0_s);
    fflush(stdout);
}

int main(int argc, char **argv)
{
    const char *input = NULL, *output = NULL, *endpoint = NULL, *endpoint_file = NULL;
    double idle_s = 300.0;
    int check_only = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int has_value = i + 1 < argc;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(a, "--check") == 0) {
            check_only = 1;
        } else if (strcmp(a, "--output") == 0 && has_value) {
            output = argv[++i];
        } else if (strcmp(a, "--endpoint") == 0 && has_value) {
            endpoint = argv[++i];
        } else if (strcmp(a, "--endpoint-file") == 0 && has_value) {
            endpoint_file = argv[++i];
        } else if (strcmp(a, "--idle-timeout") == 0 && has_value) {
            char *end;
            idle_s = strtod(argv[++i], &end);
            if (*end || end == argv[i] || idle_s != idle_s) {
                fprintf(stderr, "fem_solver: --idle-timeout: expected seconds, got \"%s\"\n", argv[i]);
                return 2;
            }
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "fem_solver: unknown option or missing value: %s\n", a);
            usage(stderr);
            return 2;
        } else if (!input) {
            input = a;
        } else {
            fprintf(stderr, "fem_solver: more than one input file: %s and %s\n", input, a);
            return 2;
        }
    }
    if (!input || (!output && !check_only)) {
        fprintf(stderr, "fem_solver: %s is required\n", !input ? "an input file" : "--output DIR");
        usage(stderr);
        return 2;
    }
    const volatile sig_atomic_t *stop = nc_signal_catch_stop();

    nc_error err;
    nc_error_clear(&err);
    fem_model model;
    fem_input_options iopt = {.warnings = stderr};
    if (fem_input_load_opt(input, &model, &iopt, &err)) {
        fprintf(stderr, "fem_solver: %s\n", err.message);
        fem_model_free(&model);
        return 1;
    }
    print_summary(&model, input, stdout);
    if (endpoint) warn_undamped_coupling(&model, input);
    if (check_only) {
        printf("fem_solver: %s: valid (checked only, nothing run)\n", input);
        fem_model_free(&model);
        return 0;
    }
    if (nc_file_make_dirs(output, &err)) {
        fprintf(stderr, "fem_solver: --output: %s\n", err.message);
        fem_model_free(&model);
        return 1;
    }
    fem_run_summary sum;
    memset(&sum, 0, sizeof sum);
    sum.max_displacement_node = -1;
    sum.overload = calloc((size_t)model.n_sets, sizeof *sum.overload);   /* NULL: not reported */
    int rc;
    settle_progress progress = {input, nc_clock_now_s(), 0.0};
    const fem_settle_watch watch = {settle_step, &progress, stop};
    if (endpoint) {
        fem_coupled_options opt = {endpoint, endpoint_file, (int)(idle_s * 1000.0), &watch};
        rc = fem_run_coupled(&model, output, &opt, stop, &sum, &err);
    } else {
        rc = fem_run_standalone(&model, output, stop, &watch, &sum, &err);
    }
    char where[96] = "";
    if (sum.max_displacement_node >= 0)
        snprintf(where, sizeof where, " at %s %g, node %d",
                 model.settings.type == FEM_STATIC ? "load factor" : "t =",
                 sum.max_displacement_time_s, sum.max_displacement_node);
    if (model.settings.initial_static && sum.initial_max_displacement_node >= 0)
        fprintf(stderr, "fem_solver: %s: started at rest in static equilibrium under the loads at "
                        "t = 0 (analysis.initial_state): %d pseudo-time steps, %d Newton iterations, "
                        "largest displacement from the reference %.6g m at node %d\n",
                input, sum.initial_steps, sum.initial_iterations,
                sum.initial_max_displacement_m, sum.initial_max_displacement_node);
    if (sum.settled_increments > 0)
        fprintf(stderr, "fem_solver: %s: %d of %ld load steps solved by pseudo-time steps (their "
                        "static Newton iteration failed or met dofs that only slack cables "
                        "hold)\n", input, sum.settled_increments, sum.steps);
    char ldlt[96] = "";
    if (sum.stats.ldlt_switch_step >= 0)
        snprintf(ldlt, sizeof ldlt, " (LDL^T from step %ld on: the matrix was indefinite)",
                 sum.stats.ldlt_switch_step);
    fprintf(stderr,
            "fem_solver: %s: %d nodes, %d elements, %ld steps, %ld Newton iterations, "
            "%ld output steps, t = %g, max |u| = %.6g m%s%s, %.3f s (assembly %.3f s, "
            "%ld factorisations %.3f s%s, %ld LU fallbacks, %ld solves ended at the rounding floor, "
            "%ld Newton steps through GMRES (an unsymmetric interface linearisation, or "
            "sliding ropes' rank-one terms) "
            "(%ld GMRES iterations, %ld short of its tolerance), "
            "%d steps retried with the semi-definite interface linearisation, "
            "%d repeated solves restarted from the start of the step)\n",
            input, model.n_nodes, model.n_elements, sum.steps, sum.newton_iterations,
            sum.output_steps, sum.final_time_s, sum.max_displacement_m, where,
            sum.max_displacement_node < 0 ? " (at the end)" : "", sum.wall_s,
            sum.stats.assembly_s, sum.stats.factorizations, sum.stats.factor_s, ldlt,
            sum.stats.lu_factorizations,
            sum.stats.roundoff_converged, sum.stats.gmres_solves, sum.stats.gmres_iterations,
            sum.stats.gmres_failures, sum.semidefinite_retries, sum.warm_start_fallbacks);
    /* each set with a breaking load: its largest force against it, a warning when exceeded */
    for (int k = 0; sum.overload && k < model.n_sets; k++)
        if (sum.overload[k].breaking_load_n > 0.0 && sum.overload[k].peak_element >= 0) {
            char line[512];
            fem_set_overload_text(&model, k, &sum.overload[k], line, sizeof line);
            fprintf(stderr, "fem_solver: %s\n", line);
        }
    free(sum.overload);
    int overload_fails = model.settings.fail_on_overload && sum.overloaded_elements > 0;
    fem_model_free(&model);
    if (rc == 1) {
        fprintf(stderr, "fem_solver: stopped by a signal; results so far are in %s\n", output);
        return 130;
    }
    if (rc && err.code == FEM_ERR_STOPPED) {
        fprintf(stderr, "fem_solver: %s\n", err.message);
        return 130;
    }
    if (rc) {
        fprintf(stderr, "fem_solver: %s\n", err.message);
        return 1;
    }
    if (overload_fails) {
        fprintf(stderr, "fem_solver: %d element%s exceeded the breaking load (analysis.fail_on_overload): "
                        "exit status 3\n", sum.overloaded_elements, sum.overloaded_elements == 1 ? "" : "s");
        return 3;
    }
    return 0;
}
