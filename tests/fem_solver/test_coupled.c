/* test_coupled — plays the coupler against the real program ($NC_BIN/fem_solver
 * --endpoint): HELLO, INTERFACE arrays, BEGIN_STEP / SOLVE (a repeated iteration restores the
 * start of the step and starts Newton from the previous solution: the same reply within
 * Newton's tolerance, to the bit when the force is unchanged) / ACCEPT_STEP, an error reply for a bad force
 * shape while the solver keeps serving, SHUTDOWN, the HDF5 monitor rows, and the exit on
 * idle timeout. The replies are compared with the same model solved in-process. A run that
 * starts in static equilibrium (analysis.initial_state "static") gives the interface where the
 * equilibrium holds it and displacements from there. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <hdf5.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "../../fem_solver/fem_analysis.h"
#include "../../fem_solver/fem_input.h"
#include "fem_test_util.h"
#include "proto.h"

static const char *cable_json =
    "{\"nodes\": [[0,0,0],[1,0,0],[2,0,0],[3,0,0]], \"elements\": [[0,1],[1,2],[2,3]],\n"
    " \"element_sets\": [{\"name\": \"c\", \"youngs_modulus_pa\": 1e9, \"area_m2\": 1.26e-4,\n"
    "   \"density_kg_m3\": 7850, \"prestress_pa\": 1e6}],\n"
    " \"supports\": [{\"nodes\": [0, 3]}], \"rayleigh\": {\"tau_per_s\": 5},\n"
    " \"monitor_nodes\": [1], \"output\": {\"interval_steps\": 5},\n"
    " \"analysis\": {\"type\": \"dynamic\", \"dt_s\": 0.001}}\n";

/* Connects to the solver listening at ep as its "fem" peer (30 s request timeout) and zeroes
 * the request and reply messages; the caller says HELLO. */
static proto_peer *connect_fem(const char *ep, proto_message *req, proto_message *rep, nc_error *err)
{
    proto_options opt;
    proto_options_default(&opt);
    opt.timeout_ms = 30000;
    proto_peer *peer;
    assert_int_equal(proto_peer_open(&peer, "fem", ep, &opt, err), 0);
    memset(req, 0, sizeof *req);
    memset(rep, 0, sizeof *rep);
    return peer;
}

static void paths(const char *tag, char *dir, char *epfile, size_t size)
{
    const char *tmp = getenv("NC_TMP");
    if (!tmp || !*tmp) tmp = "/tmp";
    snprintf(dir, size, "%s/%d-%s-out", tmp, (int)getpid(), tag);
    snprintf(epfile, size, "%s/%d-%s-endpoint", tmp, (int)getpid(), tag);
    unlink(epfile);
}

/* Starts fem_solver on json with its outputs under dir (named by tag), connects as its "fem"
 * peer and says HELLO; the solver's pid in *pid. */
static proto_peer *start_fem(const char *json, const char *tag, char *dir, size_t size, pid_t *pid,
                             proto_message *req, proto_message *rep, nc_error *err)
{
    char epfile[600], ep[256];
    paths(tag, dir, epfile, size < sizeof epfile ? size : sizeof epfile);
    *pid = fem_test_spawn(json, dir, epfile, "30");
    assert_true(*pid > 0);
    if (fem_test_read_endpoint(epfile, ep, sizeof ep)) {
        kill(*pid, SIGKILL);
        fail_msg("fem_solver did not write its endpoint file");
    }
    proto_peer *peer = connect_fem(ep, req, rep, err);
    if (proto_peer_hello(peer, rep, err)) fail_msg("%s", err->message);
    return peer;
}

static long h5_rows(const char *file, const char *dataset)
{
    hid_t f = H5Fopen(file, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) return -1;
    hid_t d = H5Dopen2(f, dataset, H5P_DEFAULT);
    long rows = -1;
    if (d >= 0) {
        hid_t sp = H5Dget_space(d);
        hsize_t dims[3];
        H5Sget_simple_extent_dims(sp, dims, NULL);
        rows = (long)dims[0];
        H5Sclose(sp);
        H5Dclose(d);
    }
    H5Fclose(f);
    return rows;
}

static void test_protocol_session(void **state)
{
    (void)state;
    if (!getenv("NC_BIN")) skip();
    const char *json = fem_test_write("coupled.json", cable_json);
    char dir[600];
    pid_t pid;
    nc_error err;
    proto_message req, rep;
    proto_peer *peer = start_fem(json, "session", dir, sizeof dir, &pid, &req, &rep, &err);
    assert_string_equal(rep.role, "fem");

    proto_message_init(&req, PROTO_MSG_INTERFACE);
    if (proto_peer_request(peer, &req, &rep, &err)) fail_msg("%s", err.message);
    const int32_t *ids, *elems;
    const double *X;
    size_t n = 0, m = 0;
    assert_int_equal(proto_message_get_i32(&rep, "node_ids", 0, 0, &ids, &n, &err), 0);
    assert_int_equal(n, 4);
    for (int i = 0; i < 4; i++) assert_int_equal(ids[i], i);
    assert_int_equal(proto_message_get_f64(&rep, "coordinates", 4, 3, &X, NULL, &err), 0);
    assert_near(X[3 * 3], 3.0, 0.0);
    assert_int_equal(proto_message_get_i32(&rep, "elements", 0, 2, &elems, &m, &err), 0);
    assert_int_equal(m, 3);
    assert_int_equal(elems[2], 1);
    assert_int_equal(elems[3], 2);

    /* the same model in-process, for comparison */
    fem_model model;
    assert_int_equal(fem_input_load(json, &model, &err), 0);
    fem_analysis ref;
    assert_int_equal(fem_analysis_init(&ref, &model, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(&ref, &err), 0);

    const double dt = 1e-3;
    double force[12] = {0}, u1[12], v1[12];
    const int steps = 12;
    for (int k = 0; k < steps; k++) {
        proto_message_init(&req, PROTO_MSG_BEGIN_STEP);
        req.step = k;
        req.time_s = k * dt;
        req.dt_s = dt;
        if (proto_peer_request(peer, &req, &rep, &err)) fail_msg("%s", err.message);
        force[3 * 1 + 2] = force[3 * 2 + 2] = -100.0 * (k + 1);
        double u3[12], v3[12];
        for (int it = 1; it <= 4; it++) {
            proto_message_init(&req, PROTO_MSG_SOLVE);
            req.step = k;
            req.iteration = it;
            req.time_s = k * dt;
            req.dt_s = dt;
            /* iteration 2 uses another force; 1, 3 and 4 the same one */
            double f2[12];
            memcpy(f2, force, sizeof f2);
            if (it == 2) f2[5] *= 3;
            assert_int_equal(proto_message_add_f64(&req, "force", f2, 4, 3, &err), 0);
            if (proto_peer_request(peer, &req, &rep, &err)) fail_msg("step %d: %s", k, err.message);
            const double *u, *v;
            assert_int_equal(proto_message_get_f64(&rep, "displacement", 4, 3, &u, NULL, &err), 0);
            assert_int_equal(proto_message_get_f64(&rep, "velocity", 4, 3, &v, NULL, &err), 0);
            assert_true(proto_message_has_value(&rep, "newton_iterations"));
            assert_true(proto_message_value(&rep, "residual_norm", -1) >= 0);
            if (it == 1) {
                memcpy(u1, u, sizeof u1);
                memcpy(v1, v, sizeof v1);
            } else if (it == 3) {
                /* solved again from iteration 2's solution (the warm start of a repeated
                 * step): the same solution within Newton's displacement tolerance, 1e-9 m */
                for (int i = 0; i < 12; i++) assert_near(u[i], u1[i], 1e-9);
                memcpy(u3, u, sizeof u3);
                memcpy(v3, v, sizeof v3);
            } else if (it == 4) {
                /* from its own solution: no Newton iteration, the same reply to the bit */
                assert_int_equal((long)proto_message_value(&rep, "newton_iterations", -1), 0);
                assert_memory_equal(u3, u, sizeof u3);
                assert_memory_equal(v3, v, sizeof v3);
            }
        }
        /* in-process reference; same code, same operations: identical to the last bit in the
         * first step; later ones start from the accepted iteration 4, within Newton's
         * tolerance of this reference's start */
        for (int i = 0; i < 12; i++) ref.f_coupling[i] = force[i];
        assert_int_equal(fem_analysis_step(&ref, dt, &err), 0);
        if (k == 0) assert_memory_equal(ref.cur.u, u1, sizeof u1);
        for (int i = 0; i < 12; i++) assert_near(ref.cur.u[i], u1[i], 1e-9);
        proto_message_init(&req, PROTO_MSG_ACCEPT_STEP);
        req.step = k;
        if (proto_peer_request(peer, &req, &rep, &err)) fail_msg("%s", err.message);
    }
    assert_below(u1[3 * 1 + 2], -1e-4);   /* the loaded cable moved down */

    /* a SOLVE with a wrong force shape: error reply, the solver keeps serving */
    proto_message_init(&req, PROTO_MSG_BEGIN_STEP);
    req.step = steps;
    req.time_s = steps * dt;
    req.dt_s = dt;
    assert_int_equal(proto_peer_request(peer, &req, &rep, &err), 0);
    proto_message_init(&req, PROTO_MSG_SOLVE);
    req.iteration = 1;
    req.dt_s = dt;
    assert_int_equal(proto_message_add_f64(&req, "force", force, 3, 3, &err), 0);
    assert_int_equal(proto_peer_request(peer, &req, &rep, &err), -1);
    assert_int_equal(err.code, PROTO_ERR_PEER);
    print_message("expected error reply: %s\n", err.message);
    assert_non_null(strstr(err.message, "force"));

    proto_message_init(&req, PROTO_MSG_SHUTDOWN);
    if (proto_peer_request(peer, &req, &rep, &err)) fail_msg("%s", err.message);
    int code = fem_test_wait_exit(pid, 30);
    assert_int_equal(code, 1);   /* a command failed during the run: non-zero after SHUTDOWN */
    char h5[700];
    snprintf(h5, sizeof h5, "%s/fem.h5", dir);
    assert_int_equal(h5_rows(h5, "/monitor/time"), steps + 1);
    assert_int_equal(h5_rows(h5, "/monitor/displacement"), steps + 1);
    assert_true(h5_rows(h5, "/output/time") >= 3);   /* t = 0, steps 5, 10, last */
    proto_message_free(&req);
    proto_message_free(&rep);
    proto_peer_close(peer);
    fem_analysis_free(&ref);
    fem_model_free(&model);
}

/* analysis.initial_state "static" on the cable with self-weight: INTERFACE's coordinates are
 * the reference plus the equilibrium's displacement (computed in-process, the same code); a
 * SOLVE without force, with a contact linearisation about the start position (jacobian
 * displacement 0), replies displacement and velocity 0 within 1e-12 (the cable hangs still
 * where the coordinates say, and the linearisation point is taken in the protocol's
 * displacements); one with a force replies the in-process step's displacement less the
 * equilibrium's, within Newton's 1e-9 m. */
static void test_initial_state_interface(void **state)
{
    (void)state;
    if (!getenv("NC_BIN")) skip();
    char text[1200];
    snprintf(text, sizeof text, "%s", cable_json);
    char *analysis = strstr(text, "\"analysis\"");
    assert_non_null(analysis);
    snprintf(analysis, sizeof text - (size_t)(analysis - text),
             "\"self_weight\": true,\n \"analysis\": {\"type\": \"dynamic\", \"dt_s\": 0.001, "
             "\"initial_state\": \"static\"}}\n");
    const char *json = fem_test_write("coupled_settled.json", text);
    char dir[600];
    pid_t pid;
    nc_error err;
    proto_message req, rep;
    proto_peer *peer = start_fem(json, "settled", dir, sizeof dir, &pid, &req, &rep, &err);

    fem_model model;
    assert_int_equal(fem_input_load(json, &model, &err), 0);
    assert_int_equal(model.settings.initial_static, 1);
    fem_analysis ref;
    int iterations, steps;
    assert_int_equal(fem_analysis_init(&ref, &model, &err), 0);
    if (fem_analysis_initial_equilibrium(&ref, &iterations, &steps, &err)) fail_msg("%s", err.message);
    assert_int_equal(fem_analysis_initial_acceleration(&ref, &err), 0);
    double u0[12];
    memcpy(u0, ref.cur.u, sizeof u0);
    assert_below(u0[3 * 1 + 2], -1e-4);   /* the cable sags under its weight */

    proto_message_init(&req, PROTO_MSG_INTERFACE);
    if (proto_peer_request(peer, &req, &rep, &err)) fail_msg("%s", err.message);
    const double *X;
    assert_int_equal(proto_message_get_f64(&rep, "coordinates", 4, 3, &X, NULL, &err), 0);
    for (int i = 0; i < 12; i++) assert_near(X[i], model.X[i] + u0[i], 0.0);

    const double dt = 1e-3;
    /* the arrays a request refers to (it does not copy them) live until it is sent */
    const int32_t nodes[2] = {1, 1};
    const double K[9] = {1e5, 0, 0, 0, 1e5, 0, 0, 0, 1e5}, zero[12] = {0};
    for (int k = 0; k < 2; k++) {
        proto_message_init(&req, PROTO_MSG_BEGIN_STEP);
        req.step = k;
        req.time_s = k * dt;
        req.dt_s = dt;
        if (proto_peer_request(peer, &req, &rep, &err)) fail_msg("%s", err.message);
        double force[12] = {0};
        if (k == 1) force[3 * 1 + 2] = -200.0;
        proto_message_init(&req, PROTO_MSG_SOLVE);
        req.step = k;
        req.iteration = 1;
        req.time_s = k * dt;
        req.dt_s = dt;
        assert_int_equal(proto_message_add_f64(&req, "force", force, 4, 3, &err), 0);
        if (k == 0) {
            /* a contact linearisation about the interface's start position (0 in the
             * protocol's displacements): no force there, so the cable stays put; an FEM that
             * took the point in its own displacements would feel K u0 */
            assert_int_equal(proto_message_add_i32(&req, "jacobian_nodes", nodes, 1, 2, &err), 0);
            assert_int_equal(proto_message_add_f64(&req, "jacobian_stiffness", K, 1, 9, &err), 0);
            assert_int_equal(proto_message_add_f64(&req, "jacobian_displacement", zero, 4, 3, &err), 0);
            assert_int_equal(proto_message_add_f64(&req, "jacobian_velocity", zero, 4, 3, &err), 0);
        }
        if (proto_peer_request(peer, &req, &rep, &err)) fail_msg("step %d: %s", k, err.message);
        const double *u, *v;
        assert_int_equal(proto_message_get_f64(&rep, "displacement", 4, 3, &u, NULL, &err), 0);
        assert_int_equal(proto_message_get_f64(&rep, "velocity", 4, 3, &v, NULL, &err), 0);
        for (int i = 0; i < 12; i++) ref.f_coupling[i] = force[i];
        assert_int_equal(fem_analysis_step(&ref, dt, &err), 0);
        for (int i = 0; i < 12; i++) {
            assert_near(u[i], k == 0 ? 0.0 : ref.cur.u[i] - u0[i], k == 0 ? 1e-12 : 1e-9);
            assert_near(v[i], k == 0 ? 0.0 : ref.cur.v[i], k == 0 ? 1e-12 : 1e-6);
        }
        if (k == 1) assert_below(u[3 * 1 + 2], -1e-6);   /* the force moved it from the sag */
        proto_message_init(&req, PROTO_MSG_ACCEPT_STEP);
        req.step = k;
        if (proto_peer_request(peer, &req, &rep, &err)) fail_msg("%s", err.message);
    }
    proto_message_init(&req, PROTO_MSG_SHUTDOWN);
    if (proto_peer_request(peer, &req, &rep, &err)) fail_msg("%s", err.message);
    assert_int_equal(fem_test_wait_exit(pid, 30), 0);
    proto_message_free(&req);
    proto_message_free(&rep);
    proto_peer_close(peer);
    fem_analysis_free(&ref);
    fem_model_free(&model);
}

/* Newton failure (max_iterations = 1, a large force): a retryable error reply naming Newton
 * and the step; the solver rolls back and keeps serving: the same step with no force then
 * succeeds from the untouched start state (cable at rest: zero displacement), and the
 * solver exits 0 (the coupler handles retryable failures). */
static void test_newton_failure(void **state)
{
    (void)state;
    if (!getenv("NC_BIN")) skip();
    char text[2048];
    const char *at = strstr(cable_json, "\"dt_s\"");
    assert_non_null(at);
    snprintf(text, sizeof text, "%.*s\"max_iterations\": 1, %s", (int)(at - cable_json),
             cable_json, at);
    const char *json = fem_test_write("newton.json", text);
    char dir[600];
    pid_t pid;
    nc_error err;
    proto_message req, rep;
    proto_peer *peer = start_fem(json, "newton", dir, sizeof dir, &pid, &req, &rep, &err);
    proto_message_init(&req, PROTO_MSG_BEGIN_STEP);
    req.step = 0;
    req.dt_s = 1e-3;
    assert_int_equal(proto_peer_request(peer, &req, &rep, &err), 0);
    double force[12] = {0};
    force[3 * 1 + 2] = -1e6;
    for (int it = 1; it <= 2; it++) {
        proto_message_init(&req, PROTO_MSG_SOLVE);
        req.step = 0;
        req.iteration = it;
        req.dt_s = 1e-3;
        if (it == 2) force[3 * 1 + 2] = 0.0;
        assert_int_equal(proto_message_add_f64(&req, "force", force, 4, 3, &err), 0);
        int rc = proto_peer_request(peer, &req, &rep, &err);
        if (it == 1) {
            assert_int_equal(rc, -1);
            print_message("expected error reply: %s\n", err.message);
            assert_non_null(strstr(err.message, "Newton did not converge"));
            assert_non_null(strstr(err.message, "step 0"));
            /* and where: the node and dof with the largest residual */
            assert_non_null(strstr(err.message, "largest residual"));
            assert_non_null(strstr(err.message, " at node "));
            /* retryable: a smaller step may converge (the coupler decides) */
            assert_int_equal(err.code, PROTO_ERR_STEP_FAILED);
        } else {
            if (rc) fail_msg("%s", err.message);
            const double *u;
            assert_int_equal(proto_message_get_f64(&rep, "displacement", 4, 3, &u, NULL, &err), 0);
            for (int i = 0; i < 12; i++) assert_near(u[i], 0.0, 0.0);
        }
    }
    proto_message_init(&req, PROTO_MSG_SHUTDOWN);
    assert_int_equal(proto_peer_request(peer, &req, &rep, &err), 0);
    /* a retryable failure is the coupler's to handle, not an error of the FEM's run */
    assert_int_equal(fem_test_wait_exit(pid, 30), 0);
    proto_message_free(&req);
    proto_message_free(&rep);
    proto_peer_close(peer);
}

/* No command within --idle-timeout: the solver exits non-zero. It never began a step, so it
 * created no results (a run that is about to RESUME must find its fem.h5 untouched). */
static void test_idle_timeout(void **state)
{
    (void)state;
    if (!getenv("NC_BIN")) skip();
    const char *json = fem_test_write("idle.json", cable_json);
    char dir[600], epfile[600], ep[256];
    paths("idle", dir, epfile, sizeof dir);
    pid_t pid = fem_test_spawn(json, dir, epfile, "1");
    assert_int_equal(fem_test_read_endpoint(epfile, ep, sizeof ep), 0);
    int code = fem_test_wait_exit(pid, 30);
    assert_int_equal(code, 1);
    char h5[700];
    snprintf(h5, sizeof h5, "%s/fem.h5", dir);
    struct stat st;
    assert_int_not_equal(stat(h5, &st), 0);
}

int main(void)
{
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_protocol_session),
        cmocka_unit_test(test_initial_state_interface),
        cmocka_unit_test(test_newton_failure),
        cmocka_unit_test(test_idle_timeout),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
