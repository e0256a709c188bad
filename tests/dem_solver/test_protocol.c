/* test_protocol — bin/dem_solver as a coupling participant, driven through the real protocol
 * (proto_peer_*) the way the coupler drives it: INTERFACE, BEGIN_STEP / SOLVE / ACCEPT_STEP,
 * a repeated SOLVE (restore) giving identical forces, a malformed SOLVE answered with an error
 * while the solver keeps serving, SHUTDOWN. A sphere dropped on a fixed two-edge wall comes to
 * rest: the returned nodal forces sum to its weight. Needs NC_BIN (skipped otherwise). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "nc_error.h"
#include "nc_file.h"
#include "proto.h"

static void test_coupled_drop_on_two_edges(void **state)
{
    (void)state;
    const char *bin = getenv("NC_BIN");
    if (!bin || !bin[0]) {
        print_message("NC_BIN not set: skipped\n");
        skip();
    }
    const char *tmp = getenv("NC_TMP");
    if (!tmp || !tmp[0]) tmp = "/tmp";
    char dir[512], input[600], epfile[600], outdir[600], exe[600], h5[700];
    snprintf(dir, sizeof dir, "%s/dem_protocol.%ld", tmp, (long)getpid());
    nc_error err;
    if (nc_file_make_dirs(dir, &err)) {
        print_error("%s\n", err.message);
        fail();
    }
    snprintf(input, sizeof input, "%s/dem.json", dir);
    snprintf(epfile, sizeof epfile, "%s/endpoint", dir);
    snprintf(outdir, sizeof outdir, "%s/out", dir);
    snprintf(exe, sizeof exe, "%s/dem_solver", bin);
    FILE *f = fopen(input, "w");
    assert_non_null(f);
    fprintf(f, "{\"materials\": [{\"name\": \"rock\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2,"
               " \"density_kg_m3\": 2500, \"restitution\": 0.3, \"friction\": 0.5}],"
               " \"particles\": [{\"position\": [0.3, 0, 0.15], \"radius\": 0.1}],"
               " \"net_wall\": {\"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2, \"friction\": 0.3},"
               " \"dt_s\": 2e-5, \"output_interval_s\": 0.05}\n");
    fclose(f);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        freopen("/dev/null", "w", stdout);
        execl(exe, exe, input, "--endpoint", "tcp://127.0.0.1:*", "--endpoint-file", epfile,
              "--output", outdir, "--idle-timeout", "30", (char *)NULL);
        _exit(127);
    }
    char endpoint[256] = "";
    for (int k = 0; k < 300 && !endpoint[0]; k++) { /* up to 30 s (sanitizer builds are slow) */
        FILE *e = fopen(epfile, "r");
        if (e) {
            if (!fgets(endpoint, sizeof endpoint, e)) endpoint[0] = '\0';
            fclose(e);
            endpoint[strcspn(endpoint, "\n")] = '\0';
        }
        if (!endpoint[0]) usleep(100000);
    }
    assert_true(endpoint[0] != '\0');

    proto_options opt;
    proto_options_default(&opt);
    opt.timeout_ms = 60000;
    proto_peer *peer;
    assert_int_equal(proto_peer_open(&peer, "dem", endpoint, &opt, &err), 0);
    proto_message req, rep;
    memset(&req, 0, sizeof req);
    memset(&rep, 0, sizeof rep);
    assert_int_equal(proto_peer_hello(peer, &rep, &err), 0);
    assert_string_equal(rep.role, "dem");

    /* wall: three nodes on the x axis, two edges; the sphere lands on edge 0 at x = 0.3 */
    int32_t ids[3] = {10, 11, 12}, elements[4] = {0, 1, 1, 2};
    double xyz[9] = {0, 0, 0, 0.5, 0, 0, 1, 0, 0}, zero[9] = {0};
    proto_message_init(&req, PROTO_MSG_INTERFACE);
    assert_int_equal(proto_message_add_i32(&req, "node_ids", ids, 3, 0, &err), 0);
    assert_int_equal(proto_message_add_f64(&req, "coordinates", xyz, 3, 3, &err), 0);
    assert_int_equal(proto_message_add_i32(&req, "elements", elements, 2, 2, &err), 0);
    assert_int_equal(proto_peer_request(peer, &req, &rep, &err), 0);

    double dt = 1e-3, force[9] = {0}, first[9];
    double near = 0, contacts = 0, substeps = 0;
    for (long step = 0; step < 800; step++) { /* 0.8 s: lands, bounces, rests */
        proto_message_init(&req, PROTO_MSG_BEGIN_STEP);
        req.step = step;
        req.time_s = (double)step * dt;
        req.dt_s = dt;
        assert_int_equal(proto_peer_request(peer, &req, &rep, &err), 0);
        int iterations = step == 400 ? 2 : 1;
        for (int it = 1; it <= iterations; it++) {
            proto_message_init(&req, PROTO_MSG_SOLVE);
            req.step = step;
            req.iteration = it;
            req.time_s = (double)step * dt;
            req.dt_s = dt;
            proto_message_add_f64(&req, "displacement", zero, 3, 3, &err);
            proto_message_add_f64(&req, "velocity", zero, 3, 3, &err);
            if (proto_peer_request(peer, &req, &rep, &err)) {
                print_error("%s\n", err.message);
                fail();
            }
            const double *fp;
            assert_int_equal(proto_message_get_f64(&rep, "force", 3, 3, &fp, NULL, &err), 0);
            memcpy(force, fp, sizeof force);
            if (it == 1) memcpy(first, force, sizeof first);
            else assert_memory_equal(first, force, sizeof force); /* restore: identical */
            near = proto_message_value(&rep, "near_interface", -1);
            contacts = proto_message_value(&rep, "contacts", -1);
            substeps = proto_message_value(&rep, "substeps", -1);
        }
        proto_message_init(&req, PROTO_MSG_ACCEPT_STEP);
        req.step = step;
        assert_int_equal(proto_peer_request(peer, &req, &rep, &err), 0);
    }
    double m = 4.0 / 3.0 * M_PI * 1e-3 * 2500, W = m * 9.81;
    double sum = force[2] + force[5] + force[8];
    print_message("at rest: nodal forces z %.4f %.4f %.4f N, sum %.4f N, weight %.4f N, near %g, "
                  "contacts %g, substeps %g\n", force[2], force[5], force[8], sum, W, near,
                  contacts, substeps);
    assert_near(-sum, W, 1e-3 * W);             /* 0.1 % */
    assert_near(-force[2], 0.4 * W, 2e-3 * W);   /* lever rule: x = 0.3 on [0, 0.5] */
    assert_near(-force[5], 0.6 * W, 2e-3 * W);
    assert_true(near == 1.0 && contacts == 1.0 && substeps == 50.0);

    /* a SOLVE with a wrong shape gets an error reply; the solver keeps serving */
    proto_message_init(&req, PROTO_MSG_BEGIN_STEP);
    req.step = 800;
    req.time_s = 800 * dt;
    req.dt_s = dt;
    assert_int_equal(proto_peer_request(peer, &req, &rep, &err), 0);
    proto_message_init(&req, PROTO_MSG_SOLVE);
    req.step = 800;
    req.iteration = 1;
    req.dt_s = dt;
    proto_message_add_f64(&req, "displacement", zero, 2, 3, &err);
    proto_message_add_f64(&req, "velocity", zero, 2, 3, &err);
    assert_int_equal(proto_peer_request(peer, &req, &rep, &err), -1);
    assert_int_equal(err.code, PROTO_ERR_PEER);
    print_message("error reply: %s\n", err.message);
    assert_non_null(strstr(err.message, "displacement"));

    proto_message_init(&req, PROTO_MSG_SHUTDOWN);
    assert_int_equal(proto_peer_request(peer, &req, &rep, &err), 0);
    proto_message_free(&req);
    proto_message_free(&rep);
    proto_peer_close(peer);
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    /* a command failed during the run: non-zero exit after SHUTDOWN, files closed */
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 1);
    snprintf(h5, sizeof h5, "%s/dem.h5", outdir);
    struct stat st;
    assert_int_equal(stat(h5, &st), 0);
    snprintf(h5, sizeof h5, "%s/particles.xdmf", outdir);
    assert_int_equal(stat(h5, &st), 0);
    snprintf(h5, sizeof h5, "%s/dem_net.xdmf", outdir);
    assert_int_equal(stat(h5, &st), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_coupled_drop_on_two_edges),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
