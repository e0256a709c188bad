/* fem_bench — timings of the FEM solver on square cable nets (`make bench`): static Newton
 * under a centre point load and a 200-step dynamic run, per Newton iteration split into
 * assembly and factorisation (+ solve), for 41x41, 81x81 and 161x161 nodes; with a barrier's
 * fem.json as argument (make bench: cases/barrier_mel), also 200 dynamic steps of that
 * structure alone under self-weight and prestress (sliding ropes, brakes, posts).
 *
 *   fem_bench [BARRIER_FEM_JSON]
 *   fem_bench --static N                 the N x N net's static solve alone, one line:
 *                                        "static N setup_s solve_s iterations w_centre_m
 *                                        largest_strain"
 *   fem_bench --write-calculix N FILE    the same net as a CalculiX input (run_bench.sh) */
#include "../fem_analysis.h"
#include "../fem_input.h"
#include "nc_clock.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int centre_node(int count) { return count / 2 + count * (count / 2); }

static int build_net(fem_model *m, int count, nc_error *err)
{
    fem_model_init(m, "bench-net");
    /* 3 m x 3 m net of the paper's prestressed cable (section 7.2 properties) */
    fem_element_set set = {"net", 1e9, 1.26e-4, 7850, 1e6, FEM_CABLE, 0.0};
    if (fem_model_add_set(m, &set, err) < 0) return -1;
    double o[3] = {0, 0, 0}, e1[3] = {3, 0, 0}, e2[3] = {0, 3, 0};
    if (fem_model_generate_net(m, o, e1, e2, count, count, 0, err)) return -1;
    const fem_node_set *b = fem_model_find_node_set(m, "boundary");
    for (int i = 0; i < b->count; i++)
        for (int c = 0; c < 3; c++) m->fixed[3 * b->nodes[i] + c] = 1;
    m->f_point[3 * centre_node(count) + 2] = -2000.0;
    m->tau_per_s = 5.0;
    return fem_model_finalize(m, err);
}

/* Axial force of a cable element at elongation dl (m): N = A (E ε_GL + S_pre) l / L0, zero
 * where that is negative (slack). The law of fem_cable_response, written out again here on
 * purpose: the CalculiX comparison checks the solver against the law, not against itself. */
static double cable_axial_force(double L0, double EA, double AS_pre, double dl)
{
    const double l = L0 + dl;
    const double AS_tot = EA * (l * l - L0 * L0) / (2.0 * L0 * L0) + AS_pre;
    return AS_tot > 0.0 ? AS_tot * l / L0 : 0.0;
}

/* Equal within 1e-12: lengths computed from generated coordinates differ by round-off. */
static int same(double a, double b) { return fabs(a - b) <= 1e-12 * fmax(fabs(a), fabs(b)); }

/* The N x N net of build_net as a CalculiX input (fem_solver/bench/run_bench.sh,
 * tests/fem_solver/test_calculix.sh): each element an axial spring (SPRINGA, its force along
 * the deformed chord, NLGEOM) whose force–elongation table is the cable's law above, one
 * table per set of equal (L0, EA, A S_pre) (equal to 1e-12: the lengths of a generated grid
 * differ by round-off); the supports and the point loads of the model; one static step; the
 * centre node's displacement printed to the .dat file (node set CENTRE). Numbers go out in
 * exponent form: CalculiX reads at most 20 characters per entry and takes an entry without
 * a decimal point in a table for a dof. */
static int write_calculix(int count, const char *path, nc_error *err)
{
    fem_model m;
    if (build_net(&m, count, err)) return -1;
    FILE *f = fopen(path, "w");
    if (!f) {
        fem_model_free(&m);
        return nc_error_set(err, 1, "%s: cannot write the CalculiX input", path);
    }
    fprintf(f, "** fem_bench: %dx%d cable net as axial springs with the cable's force law\n*NODE\n",
            count, count);
    for (int i = 0; i < m.n_nodes; i++)
        fprintf(f, "%d, %.12e, %.12e, %.12e\n", i + 1, m.X[3 * i], m.X[3 * i + 1], m.X[3 * i + 2]);
    int *group = malloc((size_t)m.n_elements * sizeof *group);
    for (int e = 0; group && e < m.n_elements; e++) {
        group[e] = -1;
        for (int g = 0; g < e && group[e] < 0; g++)
            if (group[g] == g && same(m.L0[g], m.L0[e]) && same(m.EA[g], m.EA[e]) &&
                same(m.AS[g], m.AS[e]))
                group[e] = g;
        if (group[e] < 0) group[e] = e;
    }
    for (int g = 0; group && g < m.n_elements; g++) {
        if (group[g] != g) continue;
        fprintf(f, "*ELEMENT, TYPE=SPRINGA, ELSET=NET%d\n", g + 1);
        for (int e = 0; e < m.n_elements; e++)
            if (group[e] == g)
                fprintf(f, "%d, %d, %d\n", e + 1, m.conn[2 * e] + 1, m.conn[2 * e + 1] + 1);
        fprintf(f, "*SPRING, ELSET=NET%d, NONLINEAR\n", g + 1);
        for (int k = -1; k <= 62; k++) {
            /* strain -5 % (slack), then -0.2 % ... +2.5 % every 1e-3 where the solutions lie
             * (largest 1.0-1.4 %; linear interpolation misses the law by at most
             * (1e-3 L0)^2 / 8 N'' = 3.75e-7 EA, 0.047 N against the prestress's 126 N), then
             * every 0.5 % up to 20 % for Newton's iterates on the way. CalculiX looks a
             * spring's force up row by row: a longer table costs it time in proportion. */
            const double strain = k < 0 ? -0.05 : k <= 27 ? -0.002 + 1e-3 * k
                                                           : 0.025 + 0.005 * (k - 27);
            const double dl = strain * m.L0[g];
            fprintf(f, "%.12e, %.12e\n", cable_axial_force(m.L0[g], m.EA[g], m.AS[g], dl), dl);
        }
    }
    fprintf(f, "*BOUNDARY\n");
    for (int i = 0; i < 3 * m.n_nodes; i++)
        if (m.fixed[i]) fprintf(f, "%d, %d, %d\n", i / 3 + 1, i % 3 + 1, i % 3 + 1);
    /* CalculiX's own load stepping from a tenth of the load (from the full load its Newton
     * iteration diverges); residual and correction tolerances (*CONTROLS R_n, C_n) 1e-7 of
     * the mean force and displacement instead of its defaults 5e-3 and 1e-2, so that both
     * solvers converge far below the difference compared */
    fprintf(f, "*NSET, NSET=CENTRE\n%d\n*STEP, NLGEOM, INC=1000\n*STATIC\n0.1, 1.\n"
            "*CONTROLS, PARAMETERS=FIELD\n1.e-7, 1.e-7\n*CLOAD\n", centre_node(count) + 1);
    for (int i = 0; i < 3 * m.n_nodes; i++)
        if (m.f_point[i] != 0.0) fprintf(f, "%d, %d, %.12e\n", i / 3 + 1, i % 3 + 1, m.f_point[i]);
    fprintf(f, "*NODE PRINT, NSET=CENTRE\nU\n*END STEP\n");
    const int failed = !group || ferror(f);
    free(group);
    fem_model_free(&m);
    if (fclose(f) || failed) return nc_error_set(err, 1, "%s: writing the CalculiX input failed", path);
    return 0;
}

typedef struct result {
    int count, elements, dofs, nnz;
    double setup_s, static_s, static_iter, asm_ms, fact_ms, solve_ms;
    double dyn_s, dyn_iter, dyn_asm_ms, dyn_fact_ms, static_facs, dyn_facs, dyn_cg;
    double w_centre, max_strain;
} result;

static int run(int count, int dynamic, result *r, nc_error *err)
{
    memset(r, 0, sizeof *r);
    fem_model m;
    fem_analysis s;
    memset(&s, 0, sizeof s);
    double t0 = nc_clock_now_s();
    if (build_net(&m, count, err) || fem_analysis_init(&s, &m, err)) return -1;
    r->setup_s = nc_clock_now_s() - t0;
    r->count = count;
    r->elements = m.n_elements;
    r->dofs = s.neq;
    r->nnz = s.K.nnz;
    m.settings.type = FEM_STATIC;
    t0 = nc_clock_now_s();
    if (fem_analysis_static(&s, 1.0, err)) return -1;
    r->static_s = nc_clock_now_s() - t0;
    fem_stats st = s.stats;
    r->static_iter = st.iterations;
    r->asm_ms = 1e3 * st.assembly_s / st.assemblies;
    r->fact_ms = 1e3 * st.factor_s / st.factorizations;
    r->solve_ms = 1e3 * st.solve_s / st.solves;
    r->static_facs = st.factorizations;
    r->w_centre = -s.cur.u[3 * centre_node(count) + 2];
    for (int e = 0; e < m.n_elements; e++) {
        const int a = 3 * m.conn[2 * e], b = 3 * m.conn[2 * e + 1];
        double l2 = 0.0;
        for (int c = 0; c < 3; c++) {
            const double d = m.X[b + c] + s.cur.u[b + c] - m.X[a + c] - s.cur.u[a + c];
            l2 += d * d;
        }
        r->max_strain = fmax(r->max_strain, sqrt(l2) / m.L0[e] - 1.0);
    }
    if (dynamic) {
        /* from the reference state, 200 steps of 1 ms */
        fem_analysis_free(&s);
        m.settings.type = FEM_DYNAMIC;
        m.self_weight = 1;
        m.settings.load_ramp_s = 0.05;   /* load and self-weight ramped over the first 50 ms */
        if (fem_analysis_init(&s, &m, err) || fem_analysis_initial_acceleration(&s, err)) return -1;
        memset(&s.stats, 0, sizeof s.stats);
        t0 = nc_clock_now_s();
        long iters = 0;
        for (int k = 0; k < 200; k++) {
            if (fem_analysis_step(&s, 1e-3, err)) return -1;
            iters += s.stats.iterations;
        }
        r->dyn_s = nc_clock_now_s() - t0;
        r->dyn_iter = iters;
        r->dyn_asm_ms = 1e3 * s.stats.assembly_s / s.stats.assemblies;
        r->dyn_fact_ms = 1e3 * s.stats.factor_s / s.stats.factorizations;
        r->dyn_facs = s.stats.factorizations;
        r->dyn_cg = s.stats.pcg_solves ? (double)s.stats.pcg_iterations / s.stats.pcg_solves : 0;
    }
    fem_analysis_free(&s);
    fem_model_free(&m);
    return 0;
}

/* 200 dynamic steps of the barrier in `path` at its own dt, from rest */
static int run_barrier(const char *path, nc_error *err)
{
    fem_model m;
    fem_analysis s;
    memset(&s, 0, sizeof s);
    if (fem_input_load(path, &m, err)) return -1;
    m.settings.type = FEM_DYNAMIC;
    int rc = -1;
    double t0 = nc_clock_now_s();
    if (fem_analysis_init(&s, &m, err) || fem_analysis_initial_acceleration(&s, err)) goto out;
    const double setup_s = nc_clock_now_s() - t0;
    memset(&s.stats, 0, sizeof s.stats);
    long iters = 0;
    t0 = nc_clock_now_s();
    for (int k = 0; k < 200; k++) {
        if (fem_analysis_step(&s, m.settings.dt_s, err)) goto out;
        iters += s.stats.iterations;
    }
    const double run_s = nc_clock_now_s() - t0;
    const fem_stats *st = &s.stats;
    printf("barrier %s: %d nodes, %d elements, %d dofs, nnz(K) %d, %d sliding ropes (their "
           "rank-one terms outside K); setup %.3f s\n", path, m.n_nodes, m.n_elements, s.neq,
           s.K.nnz, s.lr_members, setup_s);
    printf("barrier: 200 steps of %g s in %.3f s: %ld Newton iterations, %ld factorisations of "
           "%.2f ms, assembly %.2f ms, %ld GMRES iterations (%.1f per Newton step)\n",
           m.settings.dt_s, run_s, iters, st->factorizations,
           st->factorizations ? 1e3 * st->factor_s / st->factorizations : 0.0,
           st->assemblies ? 1e3 * st->assembly_s / st->assemblies : 0.0, st->gmres_iterations,
           st->gmres_solves ? (double)st->gmres_iterations / st->gmres_solves : 0.0);
    rc = 0;
out:
    fem_analysis_free(&s);
    fem_model_free(&m);
    return rc;
}

/* The count argument of --static and --write-calculix: an odd number of nodes per side. */
static int parse_count(const char *text, int *count)
{
    char *end;
    long n = strtol(text, &end, 10);
    if (*end || n < 3 || n > 2001 || n % 2 == 0) {
        fprintf(stderr, "fem_bench: '%s': expected an odd number of nodes per side, 3-2001\n", text);
        return -1;
    }
    *count = (int)n;
    return 0;
}

int main(int argc, char **argv)
{
    int counts[3] = {41, 81, 161};
    result r[3];
    nc_error err;
    int count;
    if (argc > 1 && strncmp(argv[1], "--", 2) == 0 &&
        !((argc == 3 && strcmp(argv[1], "--static") == 0) ||
          (argc == 4 && strcmp(argv[1], "--write-calculix") == 0))) {
        fprintf(stderr, "usage: fem_bench [BARRIER_FEM_JSON] | --static N | "
                        "--write-calculix N FILE\n");
        return 2;
    }
    if (argc == 3 && strcmp(argv[1], "--static") == 0) {
        if (parse_count(argv[2], &count)) return 2;
        if (run(count, 0, &r[0], &err)) {
            fprintf(stderr, "fem_bench: %s\n", err.message);
            return 1;
        }
        printf("static %d %.6f %.6f %.0f %.9g %.6g\n", count, r[0].setup_s, r[0].static_s,
               r[0].static_iter, r[0].w_centre, r[0].max_strain);
        return 0;
    }
    if (argc == 4 && strcmp(argv[1], "--write-calculix") == 0) {
        if (parse_count(argv[2], &count)) return 2;
        if (write_calculix(count, argv[3], &err)) {
            fprintf(stderr, "fem_bench: %s\n", err.message);
            return 1;
        }
        return 0;
    }
    printf("fem_bench: square 3 m x 3 m cable net, edges fixed, E = 1e9 Pa, A = 1.26e-4 m^2, "
           "S_pre = 1e6 Pa, 2 kN centre load\n");
    printf("times per call: asm_ms = one assembly (residual + tangent), fac_ms = one numeric "
           "factorisation, sol_ms = one linear solve (triangular solves, or CG preconditioned by a "
           "kept factorisation); iters = Newton iterations (linear "
           "solves), facs = factorisations (modified Newton keeps a factorisation and uses it to "
           "precondition CG on the current tangent)\n");
    printf("%9s %8s %8s %9s | %8s %5s %5s %9s %8s %8s %8s | %8s %6s %5s %8s %8s\n", "net", "elements",
           "dofs", "nnz(K)", "setup_s", "iters", "facs", "static_s", "asm_ms", "fac_ms",
           "sol_ms", "dyn200_s", "iters", "facs", "asm_ms", "fac_ms");
    for (int i = 0; i < 3; i++) {
        /* the 200-step dynamic run for 41x41 and 81x81 (161x161 would take minutes) */
        if (run(counts[i], i < 2, &r[i], &err)) {
            fprintf(stderr, "fem_bench: %s\n", err.message);
            return 1;
        }
        printf("%4dx%-4d %8d %8d %9d | %8.3f %5.0f %5.0f %9.3f %8.2f %8.2f %8.2f | %8.2f %6.0f %5.0f %8.2f %8.2f\n",
               r[i].count, r[i].count, r[i].elements, r[i].dofs, r[i].nnz, r[i].setup_s,
               r[i].static_iter, r[i].static_facs, r[i].static_s, r[i].asm_ms, r[i].fact_ms,
               r[i].solve_ms, r[i].dyn_s, r[i].dyn_iter, r[i].dyn_facs, r[i].dyn_asm_ms,
               r[i].dyn_fact_ms);
        fflush(stdout);
    }
    printf("dynamic: mean CG iterations per preconditioned Newton step: %.1f (41), %.1f (81)\n",
           r[0].dyn_cg, r[1].dyn_cg);
    printf("centre deflection (static): %.4f m (41), %.4f m (81), %.4f m (161)\n", r[0].w_centre,
           r[1].w_centre, r[2].w_centre);
    for (int i = 1; i < 3; i++) {
        double ne = (double)r[i].elements / r[i - 1].elements;
        printf("growth %dx%d -> %dx%d: elements x%.2f, assembly x%.2f, factorisation x%.2f, "
               "solve x%.2f, static solve x%.2f",
               counts[i - 1], counts[i - 1], counts[i], counts[i], ne, r[i].asm_ms / r[i - 1].asm_ms,
               r[i].fact_ms / r[i - 1].fact_ms, r[i].solve_ms / r[i - 1].solve_ms,
               r[i].static_s / r[i - 1].static_s);
        if (r[i].dyn_s > 0) printf(", 200 dynamic steps x%.2f", r[i].dyn_s / r[i - 1].dyn_s);
        printf("\n");
    }
    printf("target: 81x81 static solve well under 1 s -> %.3f s (%s)\n", r[1].static_s,
           r[1].static_s < 1.0 ? "met" : "NOT met");
    if (argc > 1 && run_barrier(argv[1], &err)) {
        fprintf(stderr, "fem_bench: %s\n", err.message);
        return 1;
    }
    return 0;
}
