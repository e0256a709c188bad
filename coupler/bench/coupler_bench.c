/* coupler_bench — coupling overhead of a strongly coupled run (make bench-coupler).
 *
 *   coupler_bench BIN_DIR [steps]
 *
 * 1. Exchange cost: round trip of a SOLVE with the interface arrays of a 3 m × 3 m net
 *    (21 × 21 = 441 nodes, 0.15 m mesh) to an echo participant in a thread, over TCP on
 *    localhost, averaged over many requests.
 * 2. A strongly coupled run of the real fem_solver and dem_solver (BIN_DIR) on that net with
 *    a rock dropped on it, driven in-process by the coupler's loop over the protocol.
 * The coupler times its waits per participant and its own work; the exchange share of the
 * waits is estimated as (messages × round trip), a BEGIN_STEP or ACCEPT_STEP sent to both
 * participants at once counted once. Prints FEM solve, DEM solve and
 * exchange + coupler time and checks the target exchange + coupler < 10 %.
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../cpl_history.h"
#include "../cpl_interface.h"
#include "../cpl_loop.h"
#include "../cpl_remote.h"
#include "nc_clock.h"
#include "proto.h"

extern char **environ;

#define NET_N 21
#define NODES (NET_N * NET_N)

/* ---- 1. echo participant ---------------------------------------------------------------- */

typedef struct echo_ctx {
    proto_participant *p;
    double *u, *v;
} echo_ctx;

static void *echo_main(void *arg)
{
    echo_ctx *e = arg;
    proto_message cmd, reply;
    memset(&cmd, 0, sizeof cmd);
    memset(&reply, 0, sizeof reply);
    nc_error err;
    for (;;) {
        if (proto_participant_receive(e->p, &cmd, &err)) break;
        proto_message_init(&reply, cmd.type);
        if (cmd.type == PROTO_MSG_SOLVE) {
            proto_message_add_f64(&reply, "displacement", e->u, NODES, 3, &err);
            proto_message_add_f64(&reply, "velocity", e->v, NODES, 3, &err);
        }
        if (proto_participant_reply(e->p, &reply, &err)) break;
        if (cmd.type == PROTO_MSG_SHUTDOWN) break;
    }
    proto_message_free(&cmd);
    proto_message_free(&reply);
    return NULL;
}

/* Mean round trip of a SOLVE with interface arrays (with_arrays) or of an array-less
 * BEGIN_STEP, to an echo participant in a thread. */
static double round_trip_s(int with_arrays)
{
    static double u[3 * NODES], v[3 * NODES], f[3 * NODES];
    echo_ctx e = {NULL, u, v};
    nc_error err;
    proto_options o;
    proto_options_default(&o);
    if (proto_participant_open(&e.p, "tcp://127.0.0.1:*", "fem", "echo", "", &o, &err)) {
        fprintf(stderr, "coupler_bench: %s\n", err.message);
        return NAN;
    }
    pthread_t thread;
    pthread_create(&thread, NULL, echo_main, &e);
    cpl_remote r;
    double rtt = NAN;
    if (cpl_remote_open(&r, CPL_REMOTE_FEM, proto_participant_endpoint(e.p), 10, 10, &err) == 0) {
        r.n_nodes = NODES;
        cpl_participant p = cpl_remote_participant(&r);
        cpl_call call = {.step = 0, .iteration = 1, .time_s = 0.0, .dt_s = 1e-3};
        cpl_solve_info info;
        const int warm = 200, n = 2000;
        double t0 = 0;
        for (int i = 0; i < warm + n; i++) {
            if (i == warm) t0 = nc_clock_now_s();
            int failed = with_arrays ? p.solve(p.ctx, &call, f, NULL, u, v, &info, &err)
                                     : p.begin_step(p.ctx, &call, &err);
            if (failed) break;
        }
        rtt = (nc_clock_now_s() - t0) / n;
        cpl_remote_shutdown(&r, 5, &err);
        cpl_remote_close(&r);
    } else {
        fprintf(stderr, "coupler_bench: %s\n", err.message);
    }
    pthread_join(thread, NULL);
    proto_participant_close(e.p);
    return rtt;
}

/* the coupler's own per-step work includes writing its history, as in a real run */
static int on_iteration(void *ctx, const cpl_iteration_record *rec, nc_error *err)
{
    return cpl_history_iteration(ctx, rec, err);
}

static int on_step(void *ctx, const cpl_step_record *rec, nc_error *err)
{
    return cpl_history_step(ctx, rec, err);
}

/* ---- 2. real run ------------------------------------------------------------------------ */

static int write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    fputs(text, f);
    return fclose(f);
}

static pid_t spawn(const char *program, const char *dir, const char *name)
{
    char input[600], endpoint_file[600], log[600];
    snprintf(input, sizeof input, "%s/%s.json", dir, name);
    snprintf(endpoint_file, sizeof endpoint_file, "%s/%s.endpoint", dir, name);
    snprintf(log, sizeof log, "%s/%s.log", dir, name);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    char *argv[] = {(char *)program, input, "--endpoint", "tcp://127.0.0.1:*", "--output",
                    (char *)dir, "--endpoint-file", endpoint_file, "--idle-timeout", "120", NULL};
    pid_t pid = -1;
    if (posix_spawn(&pid, program, &fa, NULL, argv, environ) != 0) pid = -1;
    posix_spawn_file_actions_destroy(&fa);
    return pid;
}

static const char *FEM_JSON =
    "{\"description\": \"benchmark: 3 m x 3 m cable net, 0.15 m mesh, edges fixed\",\n"
    " \"net\": {\"origin_m\": [-1.5, -1.5, 0], \"edge1_m\": [3, 0, 0], \"edge2_m\": [0, 3, 0],"
    " \"count1\": 21, \"count2\": 21, \"set\": \"net\"},\n"
    " \"element_sets\": [{\"name\": \"net\", \"youngs_modulus_pa\": 1e9, \"area_m2\": 2e-4,"
    " \"density_kg_m3\": 7850, \"prestress_pa\": 2e6, \"behaviour\": \"cable\"}],\n"
    " \"supports\": [{\"nodes\": \"boundary\", \"dofs\": \"xyz\"}],\n"
    " \"self_weight\": false, \"rayleigh\": {\"tau_per_s\": 5, \"kappa_s\": 0},"
    " \"mass\": \"lumped\", \"interface\": {\"element_sets\": [\"net\"]},\n"
    " \"output\": {\"interval_steps\": 50},\n"
    " \"analysis\": {\"type\": \"dynamic\", \"integrator\": \"newmark\", \"dt_s\": 1e-3,"
    " \"end_time_s\": 10}}\n";
static const char *DEM_JSON =
    "{\"description\": \"benchmark: one 0.2 m rock hitting the net at 2 m/s\",\n"
    " \"materials\": [{\"name\": \"rock\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2,"
    " \"density_kg_m3\": 2500, \"restitution\": 0.5, \"friction\": 0.5}],\n"
    " \"particles\": [{\"position\": [0.05, 0.02, 0.22], \"radius\": 0.2, \"velocity\": [0, 0, -2],"
    " \"material\": \"rock\"}],\n"
    " \"net_wall\": {\"youngs_modulus_pa\": 1e9, \"poisson_ratio\": 0.3, \"friction\": 0.3},\n"
    " \"gravity\": [0, 0, -9.81], \"end_time_s\": 10, \"output_interval_s\": 0.05}\n";

int main(int argc, char **argv)
{
    const char *bin = argc > 1 ? argv[1] : "bin";
    long steps = argc > 2 ? atol(argv[2]) : 200;
    setenv("OMP_WAIT_POLICY", "PASSIVE", 0);   /* see scripts/run_case.sh */
    setenv("OPENBLAS_THREAD_TIMEOUT", "4", 0);  /* likewise */
    signal(SIGPIPE, SIG_IGN);

    double rtt = round_trip_s(1), rtt0 = round_trip_s(0);
    printf("coupler_bench: round trip over TCP on localhost: SOLVE with %d-node arrays "
           "(%d doubles out, %d back) %.1f us, array-less command %.1f us\n", NODES, 3 * NODES,
           6 * NODES, rtt * 1e6, rtt0 * 1e6);

    char fem_prog[600], dem_prog[600];
    snprintf(fem_prog, sizeof fem_prog, "%s/fem_solver", bin);
    snprintf(dem_prog, sizeof dem_prog, "%s/dem_solver", bin);
    if (access(fem_prog, X_OK) || access(dem_prog, X_OK)) {
        printf("coupler_bench: %s or %s missing: skipping the coupled run\n", fem_prog, dem_prog);
        return 0;
    }
    const char *tmpdir = getenv("TMPDIR");
    if (!tmpdir || !tmpdir[0]) tmpdir = P_tmpdir;
    char dir[512];
    snprintf(dir, sizeof dir, "%s/coupler_bench.XXXXXX", tmpdir);
    if (!mkdtemp(dir)) return 1;
    char path[700];
    snprintf(path, sizeof path, "%s/fem.json", dir);
    write_file(path, FEM_JSON);
    snprintf(path, sizeof path, "%s/dem.json", dir);
    write_file(path, DEM_JSON);
    pid_t fem_pid = spawn(fem_prog, dir, "fem"), dem_pid = spawn(dem_prog, dir, "dem");
    nc_error err;
    char fem_ep[600], dem_ep[600], ef[700];
    snprintf(ef, sizeof ef, "%s/fem.endpoint", dir);
    int rc = 1;
    cpl_remote fem, dem;
    memset(&fem, 0, sizeof fem);
    memset(&dem, 0, sizeof dem);
    cpl_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    double *u0 = NULL, *v0 = NULL;
    cpl_loop *loop = NULL;
    if (cpl_read_endpoint_file(ef, 30, fem_ep, sizeof fem_ep, NULL, &err)) goto out;
    snprintf(ef, sizeof ef, "%s/dem.endpoint", dir);
    if (cpl_read_endpoint_file(ef, 30, dem_ep, sizeof dem_ep, NULL, &err)) goto out;
    if (cpl_remote_open(&fem, CPL_REMOTE_FEM, fem_ep, 30, 60, &err) ||
        cpl_remote_open(&dem, CPL_REMOTE_DEM, dem_ep, 30, 60, &err) ||
        cpl_remote_interface_fem(&fem, &mesh, &u0, &v0, &err) ||
        cpl_remote_interface_dem(&dem, &mesh, &err))
        goto out;
    cpl_loop_settings s;
    cpl_loop_settings_default(&s);
    s.scheme = CPL_SCHEME_STRONG;
    s.dt_s = 1e-3;
    s.end_time_s = 1e-3 * (double)steps;
    s.tol_abs = 1e-6;
    s.max_iterations = 30;
    if (cpl_relax_settings_select(&s.relax, "aitken", &err)) goto out;
    s.relax.alpha = 0.3;
    cpl_participant pf = cpl_remote_participant(&fem), pd = cpl_remote_participant(&dem);
    cpl_history history;
    memset(&history, 0, sizeof history);
    cpl_observer obs = {&history, on_iteration, on_step, NULL, NULL};
    if (cpl_history_open(&history, dir, &s, 1, &err)) goto out;
    int run_rc = cpl_loop_create(&loop, &s, mesh.n_nodes, u0, v0, &err) ||
                 cpl_loop_run(loop, &pf, &pd, &obs, NULL, NULL, &err);
    cpl_history_close(&history, loop ? cpl_loop_timing(loop) : NULL, NULL, NULL);
    if (run_rc) goto out;
    const cpl_timing *t = cpl_loop_timing(loop);
    /* the solves, and 2 array-less commands per step (begin, accept) sent to both
     * participants at once: their round trips overlap, and the loop books the wait for the
     * pair to the FEM (awaited first), the DEM's wait only where its answer came later */
    double fem_x = (double)(2 * t->steps) * rtt0 + (double)t->fem_solves * rtt;
    double dem_x = (double)t->dem_solves * rtt;
    double exchange = fem_x + dem_x;
    double own = t->total_s - t->wait_fem_s - t->wait_dem_s;
    double fem_solve = t->wait_fem_s - fem_x;
    double dem_solve = t->wait_dem_s - dem_x;
    double share = 100.0 * (exchange + own) / t->total_s;
    printf("coupler_bench: 3 m x 3 m net (%zu interface nodes), strong/Aitken, %ld steps, "
           "%ld iterations (%ld unconverged steps)\n", mesh.n_nodes, t->steps, t->iterations,
           t->unconverged_steps);
    printf("coupler_bench: wall %.3f s = FEM solve %.3f s (%.1f%%) + DEM solve %.3f s (%.1f%%)"
           " + exchange %.3f s + coupler (incl. history) %.3f s (%.2f%%)\n", t->total_s, fem_solve,
           100.0 * fem_solve / t->total_s, dem_solve, 100.0 * dem_solve / t->total_s, exchange,
           own, share);
    printf("coupler_bench: target exchange + coupler < 10 %%: %s (run folder %s)\n",
           share < 10.0 ? "met" : "MISSED", dir);
    rc = 0;
out:
    if (rc) fprintf(stderr, "coupler_bench: %s (logs in %s)\n", err.message, dir);
    if (fem.peer) cpl_remote_shutdown(&fem, 5, &err), cpl_remote_close(&fem);
    if (dem.peer) cpl_remote_shutdown(&dem, 5, &err), cpl_remote_close(&dem);
    int status;
    for (int i = 0; i < 100; i++) {
        if (waitpid(fem_pid, &status, WNOHANG) == fem_pid) fem_pid = -1;
        if (waitpid(dem_pid, &status, WNOHANG) == dem_pid) dem_pid = -1;
        if (fem_pid < 0 && dem_pid < 0) break;
        usleep(50000);
    }
    if (fem_pid > 0) kill(fem_pid, SIGKILL), waitpid(fem_pid, &status, 0);
    if (dem_pid > 0) kill(dem_pid, SIGKILL), waitpid(dem_pid, &status, 0);
    cpl_loop_free(loop);
    cpl_mesh_free(&mesh);
    free(u0);
    free(v0);
    return rc;
}
