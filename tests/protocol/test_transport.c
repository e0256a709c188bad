/* Tests of the protocol over real sockets: a forked participant and the coupler side talk over
 * tcp and ipc; a peer that never answers, dies, sends garbage or speaks another version gives
 * the documented error; a participant with no coupler leaves after its idle time; requests to
 * two peers overlap. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <zmq.h>

#include "proto.h"

#define N_NODES 50

typedef enum { SERVE_ECHO, SERVE_SILENT, SERVE_DIE, SERVE_ERROR, SERVE_EXIT_AFTER_BEGIN } serve_mode;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void scratch_path(char *out, size_t size, const char *name)
{
    const char *dir = getenv("NC_TMP");
    snprintf(out, size, "%s/%s-%d", dir && dir[0] ? dir : "/tmp", name, (int)getpid());
}

/* Child: a participant that answers solve with 2 × the input force as displacement. On
 * BEGIN_STEP it first writes a byte to signal_fd (when >= 0) and waits up to 5 s for one on
 * wait_fd (when >= 0; an error reply without it): the overlap test's gate, so that one
 * participant answers only once the other has its BEGIN_STEP. */
static int serve(const char *endpoint, int endpoint_pipe, serve_mode mode, int delay_ms,
                 int signal_fd, int wait_fd)
{
    if (delay_ms) usleep((useconds_t)delay_ms * 1000);
    proto_options options;
    proto_options_default(&options);
    options.idle_timeout_ms = 10000;
    proto_participant *p;
    nc_error err;
    if (proto_participant_open(&p, endpoint, "fem", "test participant", "restore substeps",
                               &options, &err)) {
        fprintf(stderr, "child: %s\n", err.message);
        return 2;
    }
    if (endpoint_pipe >= 0) {
        const char *bound = proto_participant_endpoint(p);
        if (write(endpoint_pipe, bound, strlen(bound) + 1) < 0) return 2;
        close(endpoint_pipe);
    }
    proto_message command, reply;
    memset(&command, 0, sizeof command);
    memset(&reply, 0, sizeof reply);
    double displacement[N_NODES * 3];
    int rc = 0;
    for (;;) {
        if (proto_participant_receive(p, &command, &err)) {
            fprintf(stderr, "child: %s\n", err.message);
            rc = 3;
            break;
        }
        if (command.type == PROTO_MSG_SOLVE) {
            if (mode == SERVE_SILENT) { sleep(30); _exit(0); }
            if (mode == SERVE_DIE) _exit(7);
            if (mode == SERVE_ERROR) {
                proto_participant_reply_error(p, "Newton did not converge in 20 iterations", &err);
                continue;
            }
            const double *force;
            if (proto_message_get_f64(&command, "force", N_NODES, 3, &force, NULL, &err)) {
                proto_participant_reply_error(p, err.message, &err);
                continue;
            }
            for (int i = 0; i < N_NODES * 3; i++) displacement[i] = 2.0 * force[i];
            proto_message_init(&reply, PROTO_MSG_SOLVE);
            proto_message_add_f64(&reply, "displacement", displacement, N_NODES, 3, &err);
            proto_message_set_value(&reply, "newton_iterations", 4, &err);
            proto_participant_reply(p, &reply, &err);
            continue;
        }
        if (command.type == PROTO_MSG_BEGIN_STEP) {
            char byte = 1;
            if (signal_fd >= 0 && write(signal_fd, &byte, 1) != 1) rc = 4;
            struct pollfd gate = {wait_fd, POLLIN, 0};
            if (wait_fd >= 0 && (poll(&gate, 1, 5000) != 1 || read(wait_fd, &byte, 1) != 1)) {
                proto_participant_reply_error(p, "the other participant never began", &err);
                continue;
            }
        }
        proto_message_init(&reply, command.type);
        proto_participant_reply(p, &reply, &err);
        if (command.type == PROTO_MSG_SHUTDOWN) break;
        if (command.type == PROTO_MSG_BEGIN_STEP && mode == SERVE_EXIT_AFTER_BEGIN) {
            proto_participant_close(p); /* lets the reply out, then the process is gone */
            _exit(0);
        }
    }
    proto_message_free(&command);
    proto_participant_close(p);
    return rc;
}

static pid_t start_gated_child(const char *endpoint, char *bound, size_t bound_size,
                               serve_mode mode, int delay_ms, int signal_fd, int wait_fd)
{
    int fds[2] = {-1, -1};
    if (bound && pipe(fds) != 0) fail_msg("pipe");
    pid_t pid = fork();
    if (pid == 0) {
        if (fds[0] >= 0) close(fds[0]);
        _exit(serve(endpoint, fds[1], mode, delay_ms, signal_fd, wait_fd));
    }
    if (bound) {
        close(fds[1]);
        ssize_t got = read(fds[0], bound, bound_size - 1);
        assert_true(got > 0);
        bound[got] = '\0';
        close(fds[0]);
    }
    return pid;
}

static pid_t start_child(const char *endpoint, char *bound, size_t bound_size, serve_mode mode,
                         int delay_ms)
{
    return start_gated_child(endpoint, bound, bound_size, mode, delay_ms, -1, -1);
}

static int wait_child(pid_t pid)
{
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

static void exchange_full_sequence(const char *endpoint)
{
    proto_peer *peer;
    nc_error err;
    proto_options options;
    proto_options_default(&options);
    options.timeout_ms = 10000;
    assert_int_equal(proto_peer_open(&peer, "fem", endpoint, &options, &err), 0);
    proto_message request, reply;
    memset(&request, 0, sizeof request);
    memset(&reply, 0, sizeof reply);
    if (proto_peer_hello(peer, &reply, &err)) fail_msg("%s", err.message);
    assert_string_equal(reply.role, "fem");
    assert_string_equal(reply.name, "test participant");
    assert_string_equal(reply.text, "restore substeps");

    proto_message_init(&request, PROTO_MSG_BEGIN_STEP);
    request.step = 0;
    request.time_s = 0.0;
    request.dt_s = 1e-3;
    if (proto_peer_request(peer, &request, &reply, &err)) fail_msg("%s", err.message);
    assert_int_equal(reply.type, PROTO_MSG_BEGIN_STEP);

    double force[N_NODES * 3];
    for (int iteration = 1; iteration <= 3; iteration++) {
        for (int i = 0; i < N_NODES * 3; i++) force[i] = 0.5 * i + iteration;
        proto_message_init(&request, PROTO_MSG_SOLVE);
        request.step = 0;
        request.iteration = iteration;
        request.dt_s = 1e-3;
        assert_int_equal(proto_message_add_f64(&request, "force", force, N_NODES, 3, &err), 0);
        if (proto_peer_request(peer, &request, &reply, &err)) fail_msg("%s", err.message);
        const double *u;
        assert_int_equal(proto_message_get_f64(&reply, "displacement", N_NODES, 3, &u, NULL, &err), 0);
        for (int i = 0; i < N_NODES * 3; i++) assert_near(u[i], 2.0 * force[i], 0.0);
        assert_int_equal(reply.iteration, iteration); /* the reply echoes the command's counters */
        assert_near(proto_message_value(&reply, "newton_iterations", 0), 4.0, 0.0);
    }
    proto_message_init(&request, PROTO_MSG_ACCEPT_STEP);
    assert_int_equal(proto_peer_request(peer, &request, &reply, &err), 0);
    proto_message_init(&request, PROTO_MSG_SHUTDOWN);
    assert_int_equal(proto_peer_request(peer, &request, &reply, &err), 0);
    proto_message_free(&reply);
    proto_peer_close(peer);
}

static void test_tcp_exchange(void **state)
{
    (void)state;
    char bound[256];
    pid_t child = start_child("tcp://127.0.0.1:*", bound, sizeof bound, SERVE_ECHO, 0);
    assert_non_null(strstr(bound, "tcp://127.0.0.1:"));
    exchange_full_sequence(bound);
    assert_int_equal(wait_child(child), 0);
}

static void test_ipc_exchange_participant_starts_late(void **state)
{
    (void)state;
    /* the coupler connects and sends its hello before the participant has bound: any start
     * order works */
    char path[200], endpoint[256];
    scratch_path(path, sizeof path, "proto.sock");
    snprintf(endpoint, sizeof endpoint, "ipc://%s", path);
    pid_t child = start_child(endpoint, NULL, 0, SERVE_ECHO, 300);
    exchange_full_sequence(endpoint);
    assert_int_equal(wait_child(child), 0);
    unlink(path);
}

/* proto_peer_send and proto_peer_receive let requests to two peers overlap: the first peer
 * answers its BEGIN_STEP only after the second has received its own, which a request that
 * waits for the first answer before sending the second could never see (the first would
 * answer with an error after 5 s). A receive without a send is an error. */
static void test_requests_overlap(void **state)
{
    (void)state;
    int gate[2];
    assert_int_equal(pipe(gate), 0);
    char bound[2][256];
    pid_t child[2] = {
        start_gated_child("tcp://127.0.0.1:*", bound[0], sizeof bound[0], SERVE_ECHO, 0, -1, gate[0]),
        start_gated_child("tcp://127.0.0.1:*", bound[1], sizeof bound[1], SERVE_ECHO, 0, gate[1], -1)};
    close(gate[0]);
    close(gate[1]);
    proto_peer *peer[2];
    proto_options options;
    proto_options_default(&options);
    options.timeout_ms = 10000;
    nc_error err;
    proto_message request, reply;
    memset(&request, 0, sizeof request);
    memset(&reply, 0, sizeof reply);
    const char *names[2] = {"fem", "dem"};
    for (int i = 0; i < 2; i++) {
        assert_int_equal(proto_peer_open(&peer[i], names[i], bound[i], &options, &err), 0);
        if (proto_peer_hello(peer[i], &reply, &err)) fail_msg("%s", err.message);
    }
    assert_int_equal(proto_peer_receive(peer[0], &reply, &err), -1);
    assert_non_null(strstr(err.message, "participant 'fem'"));
    assert_non_null(strstr(err.message, "no request awaits a reply"));
    for (long step = 0; step < 3; step++) {
        proto_message_init(&request, PROTO_MSG_BEGIN_STEP);
        request.step = step;
        request.dt_s = 1e-3;
        for (int i = 0; i < 2; i++)
            if (proto_peer_send(peer[i], &request, &err)) fail_msg("%s", err.message);
        for (int i = 0; i < 2; i++) {
            if (proto_peer_receive(peer[i], &reply, &err)) fail_msg("%s", err.message);
            assert_int_equal(reply.type, PROTO_MSG_BEGIN_STEP);
            assert_int_equal(reply.step, step);
        }
    }
    proto_message_init(&request, PROTO_MSG_SHUTDOWN);
    for (int i = 0; i < 2; i++) {
        assert_int_equal(proto_peer_request(peer[i], &request, &reply, &err), 0);
        proto_peer_close(peer[i]);
        assert_int_equal(wait_child(child[i]), 0);
    }
    proto_message_free(&reply);
}

/* Sends one solve to a participant in `mode` and returns the error. */
static void solve_expecting_error(serve_mode mode, int timeout_ms, nc_error *err, double *elapsed)
{
    char bound[256];
    pid_t child = start_child("tcp://127.0.0.1:*", bound, sizeof bound, mode, 0);
    proto_peer *peer;
    proto_options options;
    proto_options_default(&options);
    options.timeout_ms = timeout_ms;
    assert_int_equal(proto_peer_open(&peer, "dem", bound, &options, err), 0);
    proto_message request, reply;
    memset(&request, 0, sizeof request);
    memset(&reply, 0, sizeof reply);
    if (proto_peer_hello(peer, &reply, err)) fail_msg("%s", err->message);
    double force[N_NODES * 3] = {0};
    proto_message_init(&request, PROTO_MSG_SOLVE);
    request.step = 3;
    request.iteration = 2;
    request.time_s = 0.25;
    proto_message_add_f64(&request, "force", force, N_NODES, 3, NULL);
    double start = now_s();
    assert_int_equal(proto_peer_request(peer, &request, &reply, err), -1);
    *elapsed = now_s() - start;
    proto_message_free(&reply);
    proto_peer_close(peer);
    kill(child, SIGKILL);
    wait_child(child);
}

static void test_peer_never_answers_times_out(void **state)
{
    (void)state;
    nc_error err;
    double elapsed;
    solve_expecting_error(SERVE_SILENT, 400, &err, &elapsed);
    assert_int_equal(err.code, PROTO_ERR_TIMEOUT);
    /* names the peer, its endpoint and the last message sent */
    assert_non_null(strstr(err.message, "participant 'dem' at tcp://127.0.0.1:"));
    assert_non_null(strstr(err.message, "did not answer within 0.4 s"));
    assert_non_null(strstr(err.message, "solve (step 3, iteration 2, t = 0.25 s)"));
    assert_below(0.35, elapsed);
    assert_below(elapsed, 5.0);
}

static void test_peer_dies_is_reported_before_timeout(void **state)
{
    (void)state;
    nc_error err;
    double elapsed;
    solve_expecting_error(SERVE_DIE, 20000, &err, &elapsed);
    assert_int_equal(err.code, PROTO_ERR_DISCONNECTED);
    assert_non_null(strstr(err.message, "participant 'dem'"));
    assert_non_null(strstr(err.message, "closed the connection while handling solve (step 3"));
    assert_below(elapsed, 10.0); /* far less than the 20 s timeout */
}

static void test_peer_gone_between_requests_is_reported_at_once(void **state)
{
    (void)state;
    char bound[256];
    pid_t child = start_child("tcp://127.0.0.1:*", bound, sizeof bound, SERVE_EXIT_AFTER_BEGIN, 0);
    proto_peer *peer;
    nc_error err;
    proto_options options;
    proto_options_default(&options);
    options.timeout_ms = 20000;
    assert_int_equal(proto_peer_open(&peer, "fem", bound, &options, &err), 0);
    proto_message request, reply;
    memset(&request, 0, sizeof request);
    memset(&reply, 0, sizeof reply);
    if (proto_peer_hello(peer, &reply, &err)) fail_msg("%s", err.message);
    proto_message_init(&request, PROTO_MSG_BEGIN_STEP);
    request.step = 7;
    assert_int_equal(proto_peer_request(peer, &request, &reply, &err), 0);
    assert_int_equal(wait_child(child), 0); /* the participant has exited */
    usleep(200 * 1000);                     /* let the monitor see the closed connection */
    proto_message_init(&request, PROTO_MSG_SOLVE);
    request.step = 7;
    request.iteration = 1;
    double start = now_s();
    assert_int_equal(proto_peer_request(peer, &request, &reply, &err), -1);
    assert_below(now_s() - start, 5.0); /* not the 20 s timeout */
    assert_int_equal(err.code, PROTO_ERR_DISCONNECTED);
    assert_non_null(strstr(err.message, "participant 'fem'"));
    assert_non_null(strstr(err.message, "solve (step 7, iteration 1"));
    proto_message_free(&reply);
    proto_peer_close(peer);
}

static void test_error_reply_carries_reason(void **state)
{
    (void)state;
    nc_error err;
    double elapsed;
    solve_expecting_error(SERVE_ERROR, 10000, &err, &elapsed);
    assert_int_equal(err.code, PROTO_ERR_PEER);
    assert_non_null(strstr(err.message, "reported an error for solve (step 3, iteration 2"));
    assert_non_null(strstr(err.message, "Newton did not converge in 20 iterations"));
}

static void test_unreachable_peer_times_out(void **state)
{
    (void)state;
    char path[200], endpoint[256];
    scratch_path(path, sizeof path, "nobody.sock");
    snprintf(endpoint, sizeof endpoint, "ipc://%s", path);
    proto_peer *peer;
    nc_error err;
    proto_options options;
    proto_options_default(&options);
    options.timeout_ms = 300;
    assert_int_equal(proto_peer_open(&peer, "fem", endpoint, &options, &err), 0);
    proto_message reply;
    memset(&reply, 0, sizeof reply);
    assert_int_equal(proto_peer_hello(peer, &reply, &err), -1);
    assert_int_equal(err.code, PROTO_ERR_TIMEOUT);
    assert_non_null(strstr(err.message, "participant 'fem'"));
    assert_non_null(strstr(err.message, endpoint));
    assert_non_null(strstr(err.message, "hello"));
    proto_peer_close(peer);
}

static void test_participant_idle_timeout(void **state)
{
    (void)state;
    proto_options options;
    proto_options_default(&options);
    options.idle_timeout_ms = 200;
    proto_participant *p;
    nc_error err;
    assert_int_equal(proto_participant_open(&p, "tcp://127.0.0.1:*", "dem", "idle", "", &options, &err), 0);
    proto_message command;
    memset(&command, 0, sizeof command);
    double start = now_s();
    assert_int_equal(proto_participant_receive(p, &command, &err), -1);
    assert_int_equal(err.code, PROTO_ERR_IDLE);
    assert_non_null(strstr(err.message, "idle timeout"));
    assert_below(0.15, now_s() - start);
    proto_participant_close(p);
}

/* A raw ZeroMQ client sends bytes no netcouple coupler would; the participant answers each
 * with an error reply and keeps serving. */
static void test_participant_rejects_garbage(void **state)
{
    (void)state;
    proto_options options;
    proto_options_default(&options);
    options.idle_timeout_ms = 20000;
    proto_participant *p;
    nc_error err;
    /* fork before any ZeroMQ context exists in this process (forking a process whose
     * context threads may hold locks can deadlock the child); the endpoint follows by pipe */
    int fds[2];
    assert_int_equal(pipe(fds), 0);
    pid_t child = fork();
    if (child == 0) {
        /* the client: 4 bad commands, then a good shutdown; exit code = number of error
         * replies whose text matched */
        close(fds[1]);
        char endpoint[256] = {0};
        if (read(fds[0], endpoint, sizeof endpoint - 1) <= 0) _exit(99);
        close(fds[0]);
        void *context = zmq_ctx_new();
        void *socket = zmq_socket(context, ZMQ_REQ);
        zmq_connect(socket, endpoint);
        const char *bad[4] = {
            "not json at all",
            "{\"type\":\"hello\",\"version\":3}",
            "{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"force\",\"dtype\":\"f64\",\"shape\":[1,3]}]}",
            "{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"force\",\"dtype\":\"f64\",\"shape\":[1,3]}]}",
        };
        const char *expect[4] = {"not valid JSON", "version mismatch", "needs 24 bytes", "NaN"};
        int matched = 0;
        double nan_frame[3] = {0.0, NAN, 1.0};
        for (int i = 0; i < 4; i++) {
            /* array frames first, the header last */
            if (i == 2) zmq_send(socket, nan_frame, 16, ZMQ_SNDMORE);
            if (i == 3) zmq_send(socket, nan_frame, 24, ZMQ_SNDMORE);
            zmq_send(socket, bad[i], strlen(bad[i]), 0);
            char buffer[2048] = {0};
            int n = zmq_recv(socket, buffer, sizeof buffer - 1, 0);
            if (n > 0 && strstr(buffer, "\"error\"") && strstr(buffer, expect[i])) matched++;
        }
        const char *shutdown = "{\"type\":\"shutdown\",\"version\":1}";
        zmq_send(socket, shutdown, strlen(shutdown), 0);
        char buffer[512];
        zmq_recv(socket, buffer, sizeof buffer, 0);
        zmq_close(socket);
        zmq_ctx_term(context);
        _exit(matched);
    }
    close(fds[0]);
    assert_int_equal(proto_participant_open(&p, "tcp://127.0.0.1:*", "fem", "x", "", &options, &err), 0);
    const char *bound = proto_participant_endpoint(p);
    assert_true(write(fds[1], bound, strlen(bound) + 1) > 0);
    close(fds[1]);
    proto_message command;
    memset(&command, 0, sizeof command);
    int errors = 0;
    for (;;) {
        if (proto_participant_receive(p, &command, &err)) {
            errors++;
            if (err.code != PROTO_ERR_DECODE && err.code != PROTO_ERR_VERSION)
                fail_msg("unexpected error %d: %s", err.code, err.message);
            continue;
        }
        assert_int_equal(command.type, PROTO_MSG_SHUTDOWN);
        proto_message reply;
        memset(&reply, 0, sizeof reply);
        proto_message_init(&reply, PROTO_MSG_SHUTDOWN);
        proto_participant_reply(p, &reply, &err);
        break;
    }
    assert_int_equal(errors, 4);
    assert_int_equal(wait_child(child), 4);
    proto_message_free(&command);
    proto_participant_close(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tcp_exchange),
        cmocka_unit_test(test_ipc_exchange_participant_starts_late),
        cmocka_unit_test(test_requests_overlap),
        cmocka_unit_test(test_peer_never_answers_times_out),
        cmocka_unit_test(test_peer_dies_is_reported_before_timeout),
        cmocka_unit_test(test_peer_gone_between_requests_is_reported_at_once),
        cmocka_unit_test(test_error_reply_carries_reason),
        cmocka_unit_test(test_unreachable_peer_times_out),
        cmocka_unit_test(test_participant_idle_timeout),
        cmocka_unit_test(test_participant_rejects_garbage),
    };
    return cmocka_run_group_tests_name("protocol transport", tests, NULL, NULL);
}
