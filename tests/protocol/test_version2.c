/* Tests of protocol version 2 over real sockets (protocol/proto.h): a participant serving in a
 * forked child (proto_serve, or a raw ZeroMQ REP socket that answers wrongly on purpose) and
 * the coupler side as a proto_peer or a raw ZeroMQ REQ socket. Checked: hello negotiates the
 * newest common version and echoes the session token; a version-1 coupler is served in
 * version 1; a second coupler and a version-2 command before hello are refused (counted in
 * `refused`, not `failed`) while the first coupler's run goes on; a reply of another step,
 * iteration or session, or not marked as a reply, is caught as PROTO_ERR_DECODE; a handler's
 * PROTO_ERR_STEP_FAILED reaches the coupler as PROTO_ERR_STEP_FAILED (counted in `retryable`);
 * the hello reply carries the participant's idle timeout. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <ctype.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zmq.h>

#include "proto.h"
#include "proto_serve.h"

#define N_NODES 4
#define IDLE_MS 20000   /* the child participant's idle timeout */
#define LIMIT (1u << 20)

/* ---- a participant in a child process, serving through proto_serve ----------------------- */

/* The child's solver: SOLVE returns displacement = force / k (a spring, k = 1e6 N/m) and
 * fails as Newton would (retryable) when dt is above dt_max_s; a SOLVE without the force
 * array fails for good. */
typedef struct child_solver {
    double dt_max_s;
    double displacement[N_NODES * 3];
} child_solver;

static int c_solve(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    child_solver *s = ctx;
    if (cmd->dt_s > s->dt_max_s)
        return nc_error_set(err, PROTO_ERR_STEP_FAILED, "Newton did not converge in 25 "
                            "iterations at dt = %g s", cmd->dt_s);
    const double *force;
    if (proto_message_get_f64(cmd, "force", N_NODES, 3, &force, NULL, err)) return -1;
    for (int i = 0; i < N_NODES * 3; i++) s->displacement[i] = force[i] / 1e6;
    return proto_message_add_f64(reply, "displacement", s->displacement, N_NODES, 3, err);
}

/* The spring has no history: nothing to save, nothing to restore. */
static int c_save(void *ctx, const proto_message *cmd, nc_error *err)
{
    (void)ctx; (void)cmd; (void)err;
    return 0;
}

static int c_restore(void *ctx, const proto_message *cmd, nc_error *err)
{
    (void)ctx; (void)cmd; (void)err;
    return 0;
}

/* Serves until SHUTDOWN; writes the summary to `out_fd`; exit code = proto_serve's rc. */
static int serve_child(int endpoint_fd, int out_fd, double dt_max_s)
{
    proto_options options;
    proto_options_default(&options);
    options.idle_timeout_ms = IDLE_MS;
    proto_participant *p;
    nc_error err;
    if (proto_participant_open(&p, "tcp://127.0.0.1:*", "fem", "version 2 test participant",
                               "restore", &options, &err)) {
        fprintf(stderr, "child: %s\n", err.message);
        return 2;
    }
    const char *bound = proto_participant_endpoint(p);
    if (write(endpoint_fd, bound, strlen(bound) + 1) < 0) return 2;
    close(endpoint_fd);
    child_solver solver = {dt_max_s, {0}};
    proto_serve_handlers h = {0};
    h.save_state = c_save;
    h.restore_state = c_restore;
    h.solve = c_solve;
    proto_serve_summary sum;
    memset(&sum, 0, sizeof sum);
    int rc = proto_serve(p, &h, &solver, NULL, &sum, &err);
    if (rc) fprintf(stderr, "child: %s\n", err.message);
    if (write(out_fd, &sum, sizeof sum) != (ssize_t)sizeof sum) rc = 3;
    close(out_fd);
    proto_participant_close(p);
    return rc;
}

typedef struct child {
    pid_t pid;
    int summary_fd;
    char endpoint[256];
} child;

/* Forks before this process makes a ZeroMQ context (a fork of a process whose context
 * threads hold locks can deadlock the child); the endpoint comes back by pipe. */
static void start_participant(child *c, double dt_max_s)
{
    int ep[2], out[2];
    assert_int_equal(pipe(ep), 0);
    assert_int_equal(pipe(out), 0);
    c->pid = fork();
    assert_true(c->pid >= 0);
    if (c->pid == 0) {
        close(ep[0]);
        close(out[0]);
        _exit(serve_child(ep[1], out[1], dt_max_s));
    }
    close(ep[1]);
    close(out[1]);
    ssize_t got = read(ep[0], c->endpoint, sizeof c->endpoint - 1);
    assert_true(got > 0);
    c->endpoint[got] = '\0';
    close(ep[0]);
    c->summary_fd = out[0];
}

/* Waits for the child's exit; returns its exit code and its serve summary. */
static int finish_participant(child *c, proto_serve_summary *sum)
{
    memset(sum, 0, sizeof *sum);
    ssize_t got = read(c->summary_fd, sum, sizeof *sum);
    close(c->summary_fd);
    int status = 0;
    waitpid(c->pid, &status, 0);
    assert_int_equal(got, (ssize_t)sizeof *sum);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

static proto_peer *open_peer(const char *endpoint)
{
    proto_options options;
    proto_options_default(&options);
    options.timeout_ms = 10000;
    proto_peer *peer;
    nc_error err;
    if (proto_peer_open(&peer, "fem", endpoint, &options, &err)) fail_msg("%s", err.message);
    return peer;
}

/* Sends one command through the peer; returns proto_peer_request's rc (message in err). */
static int send_command(proto_peer *peer, proto_msg_type type, long step, int iteration,
                        double dt_s, const double *force, proto_message *reply, nc_error *err)
{
    proto_message request;
    memset(&request, 0, sizeof request);
    proto_message_init(&request, type);
    request.step = step;
    request.iteration = iteration;
    request.time_s = 0.01 * (double)(step > 0 ? step : 0);
    request.dt_s = dt_s;
    if (force) proto_message_add_f64(&request, "force", force, N_NODES, 3, NULL);
    nc_error_clear(err);
    return proto_peer_request(peer, &request, reply, err);
}

/* Runs the step [begin, solve 1, solve 2, accept] through the peer; all must succeed. */
static void run_step(proto_peer *peer, long step, proto_message *reply)
{
    double force[N_NODES * 3];
    for (int i = 0; i < N_NODES * 3; i++) force[i] = -250.0 * (i % 3 == 2) + 10.0 * (double)step;
    nc_error err;
    if (send_command(peer, PROTO_MSG_BEGIN_STEP, step, 0, 1e-3, NULL, reply, &err))
        fail_msg("begin_step %ld: %s", step, err.message);
    for (int k = 1; k <= 2; k++) {
        if (send_command(peer, PROTO_MSG_SOLVE, step, k, 1e-3, force, reply, &err))
            fail_msg("solve %ld.%d: %s", step, k, err.message);
        const double *u;
        if (proto_message_get_f64(reply, "displacement", N_NODES, 3, &u, NULL, &err))
            fail_msg("%s", err.message);
        for (int i = 0; i < N_NODES * 3; i++) assert_near(u[i], force[i] / 1e6, 1e-18);
        assert_int_equal(reply->step, step);
        assert_int_equal(reply->iteration, k);
    }
    if (send_command(peer, PROTO_MSG_ACCEPT_STEP, step, 0, 1e-3, NULL, reply, &err))
        fail_msg("accept_step %ld: %s", step, err.message);
}

static void shutdown_peer(proto_peer *peer, proto_message *reply)
{
    nc_error err;
    if (send_command(peer, PROTO_MSG_SHUTDOWN, -1, 0, 0.0, NULL, reply, &err))
        fail_msg("shutdown: %s", err.message);
}

/* ---- a raw ZeroMQ socket speaking the wire format by hand -------------------------------- */

typedef struct raw {
    void *context, *socket;
} raw;

static void raw_open(raw *r, int type, const char *endpoint, int bind)
{
    r->context = zmq_ctx_new();
    r->socket = zmq_socket(r->context, type);
    int timeout = 10000, linger = 0;
    zmq_setsockopt(r->socket, ZMQ_RCVTIMEO, &timeout, sizeof timeout);
    zmq_setsockopt(r->socket, ZMQ_LINGER, &linger, sizeof linger);
    if (bind) assert_int_equal(zmq_bind(r->socket, endpoint), 0);
    else assert_int_equal(zmq_connect(r->socket, endpoint), 0);
}

static void raw_close(raw *r)
{
    zmq_close(r->socket);
    zmq_ctx_term(r->context);
}

/* Sends the frames then the header (the header is the last frame). */
static void raw_send(raw *r, const char *header, const void *frame, size_t frame_bytes)
{
    if (frame) assert_true(zmq_send(r->socket, frame, frame_bytes, ZMQ_SNDMORE) >= 0);
    assert_true(zmq_send(r->socket, header, strlen(header), 0) >= 0);
}

/* Receives one message and decodes it (copied into m's storage); the raw header text goes
 * to `text` when given. Returns the decode's rc. */
static int raw_receive(raw *r, proto_message *m, char *text, size_t text_size, nc_error *err)
{
    zmq_msg_t frames[PROTO_MAX_ARRAYS + 1];
    size_t n = 0;
    int more = 1;
    while (more && n < PROTO_MAX_ARRAYS + 1) {
        zmq_msg_init(&frames[n]);
        if (zmq_msg_recv(&frames[n], r->socket, 0) < 0) fail_msg("raw receive: %s", zmq_strerror(errno));
        more = zmq_msg_more(&frames[n]);
        n++;
    }
    assert_false(more);
    const void *data[PROTO_MAX_ARRAYS];
    size_t lengths[PROTO_MAX_ARRAYS];
    for (size_t i = 0; i + 1 < n; i++) {
        data[i] = zmq_msg_data(&frames[i]);
        lengths[i] = zmq_msg_size(&frames[i]);
    }
    const char *header = zmq_msg_data(&frames[n - 1]);
    size_t header_length = zmq_msg_size(&frames[n - 1]);
    if (text) snprintf(text, text_size, "%.*s", (int)header_length, header);
    int rc = proto_decode(m, header, header_length, data, lengths, n - 1, LIMIT, err);
    for (size_t i = 0; i < n; i++) zmq_msg_close(&frames[i]);
    return rc;
}

/* One request over a raw REQ socket; the reply must decode. */
static void raw_request(raw *r, const char *header, const void *frame, size_t frame_bytes,
                        proto_message *reply, char *text, size_t text_size)
{
    raw_send(r, header, frame, frame_bytes);
    nc_error err;
    if (raw_receive(r, reply, text, text_size, &err)) fail_msg("reply to %s: %s", header, err.message);
    assert_int_equal(reply->is_reply, 1);
}

/* ---- (a) negotiation, (f) idle timeout ------------------------------------------------- */

static int is_token(const char *s)
{
    if (strlen(s) != 16) return 0;
    for (const char *c = s; *c; c++)
        if (!isxdigit((unsigned char)*c)) return 0;
    return 1;
}

/* proto_peer_hello against proto_participant: version 2, the session echoed, the capabilities
 * and the participant's idle timeout in the reply; a step runs in version 2. */
static void test_hello_negotiates_version_2(void **state)
{
    (void)state;
    child c;
    start_participant(&c, 1.0);
    proto_peer *peer = open_peer(c.endpoint);
    proto_message reply;
    memset(&reply, 0, sizeof reply);
    nc_error err;
    assert_int_equal(proto_peer_version(peer), 0);
    if (proto_peer_hello(peer, &reply, &err)) fail_msg("%s", err.message);
    assert_int_equal(reply.version, 2);
    assert_int_equal(proto_peer_version(peer), PROTO_VERSION);
    assert_true(is_token(proto_peer_session(peer)));
    assert_string_equal(reply.session, proto_peer_session(peer));
    assert_string_equal(reply.role, "fem");
    assert_string_equal(reply.name, "version 2 test participant");
    assert_true(proto_has_capability(reply.text, "restore"));
    /* (f) the coupler compares this with its reply timeout */
    assert_true(proto_message_has_value(&reply, "idle_timeout_s"));
    assert_near(proto_message_value(&reply, "idle_timeout_s", 0.0), IDLE_MS / 1000.0, 0.0);
    run_step(peer, 0, &reply);
    assert_int_equal(reply.version, 2);
    assert_string_equal(reply.session, proto_peer_session(peer));
    shutdown_peer(peer, &reply);
    proto_message_free(&reply);
    proto_peer_close(peer);
    proto_serve_summary sum;
    assert_int_equal(finish_participant(&c, &sum), 0);
    assert_int_equal(sum.commands, 5);   /* begin, 2 solves, accept, shutdown */
    assert_int_equal(sum.solves, 2);
    assert_int_equal(sum.restores, 1);
    assert_int_equal(sum.failed, 0);
    assert_int_equal(sum.refused, 0);
    assert_int_equal(sum.rejected, 0);
}

/* Two coupler tokens are different (each coupler run is told apart from another's). */
static void test_sessions_differ(void **state)
{
    (void)state;
    proto_peer *a = open_peer("tcp://127.0.0.1:1"), *b = open_peer("tcp://127.0.0.1:1");
    assert_true(is_token(proto_peer_session(a)));
    assert_true(is_token(proto_peer_session(b)));
    assert_string_not_equal(proto_peer_session(a), proto_peer_session(b));
    proto_peer_close(a);
    proto_peer_close(b);
}

/* A version-1 coupler: hello without "versions" gets a version-1 reply without a session;
 * version-1 commands are served (also a v1 command before any hello, as v1 couplers may
 * skip it). A hello offering [1, 2, 3] agrees on 2, the newest both speak. */
static void test_version_1_coupler_served(void **state)
{
    (void)state;
    child c;
    start_participant(&c, 1.0);
    raw r;
    raw_open(&r, ZMQ_REQ, c.endpoint, 0);
    proto_message reply;
    memset(&reply, 0, sizeof reply);
    char text[2048];
    /* a version-1 command before hello is served */
    raw_request(&r, "{\"type\":\"begin_step\",\"version\":1,\"step\":0,\"dt\":0.001}", NULL, 0,
                &reply, text, sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_BEGIN_STEP);
    assert_int_equal(reply.version, 1);
    raw_request(&r, "{\"type\":\"hello\",\"version\":1,\"role\":\"coupler\",\"name\":\"old\"}", NULL,
                0, &reply, text, sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_HELLO);
    assert_int_equal(reply.version, 1);
    assert_string_equal(reply.session, "");
    assert_null(strstr(text, "\"session\""));
    double force[N_NODES * 3];
    for (int i = 0; i < N_NODES * 3; i++) force[i] = 1000.0 * (double)(i + 1);
    char header[512];
    snprintf(header, sizeof header, "{\"type\":\"solve\",\"version\":1,\"step\":0,\"iteration\":1,"
             "\"dt\":0.001,\"arrays\":[{\"name\":\"force\",\"dtype\":\"f64\",\"shape\":[%d,3]}]}",
             N_NODES);
    raw_request(&r, header, force, sizeof force, &reply, text, sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_SOLVE);
    assert_int_equal(reply.version, 1);
    const double *u;
    nc_error err;
    assert_int_equal(proto_message_get_f64(&reply, "displacement", N_NODES, 3, &u, NULL, &err), 0);
    for (int i = 0; i < N_NODES * 3; i++) assert_near(u[i], force[i] / 1e6, 1e-18);
    /* a version-2 command after a version-1 hello is refused as a version mismatch */
    raw_request(&r, "{\"type\":\"accept_step\",\"version\":2,\"session\":\"0123456789abcdef\","
                "\"step\":0}", NULL, 0, &reply, text, sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_ERROR);
    assert_non_null(strstr(reply.text, "version 2 after agreeing on version 1"));
    raw_request(&r, "{\"type\":\"accept_step\",\"version\":1,\"step\":0}", NULL, 0, &reply, text,
                sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_ACCEPT_STEP);
    raw_request(&r, "{\"type\":\"shutdown\",\"version\":1}", NULL, 0, &reply, text, sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_SHUTDOWN);
    raw_close(&r);
    proto_serve_summary sum;
    /* the version mismatch was an error of the run (rejected) */
    assert_int_equal(finish_participant(&c, &sum), 0);
    assert_int_equal(sum.steps_accepted, 1);
    assert_int_equal(sum.solves, 1);
    assert_int_equal(sum.rejected, 1);
    assert_int_equal(sum.refused, 0);
    assert_int_equal(sum.failed, 0);

    /* offered [1, 2, 3]: 2 is the newest this participant speaks */
    start_participant(&c, 1.0);
    raw_open(&r, ZMQ_REQ, c.endpoint, 0);
    raw_request(&r, "{\"type\":\"hello\",\"version\":1,\"versions\":[1,2,3],"
                "\"session\":\"00000000deadbeef\"}", NULL, 0, &reply, text, sizeof text);
    assert_int_equal(reply.version, 2);
    assert_string_equal(reply.session, "00000000deadbeef");
    raw_request(&r, "{\"type\":\"begin_step\",\"version\":2,\"session\":\"00000000deadbeef\","
                "\"step\":4,\"dt\":0.001}", NULL, 0, &reply, text, sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_BEGIN_STEP);
    assert_int_equal(reply.version, 2);
    assert_int_equal(reply.step, 4);
    assert_string_equal(reply.session, "00000000deadbeef");
    raw_request(&r, "{\"type\":\"shutdown\",\"version\":2,\"session\":\"00000000deadbeef\"}", NULL,
                0, &reply, text, sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_SHUTDOWN);
    raw_close(&r);
    assert_int_equal(finish_participant(&c, &sum), 0);
    assert_int_equal(sum.failed + sum.refused + sum.rejected, 0);
    proto_message_free(&reply);
}

/* ---- (b) a second coupler, (c) version 2 before hello --------------------------------- */

/* While coupler A runs, coupler B (its own token) says hello and sends commands: each is
 * refused naming the other coupler, A's run goes on undisturbed, and the participant counts
 * the refusals in `refused`, not in `failed`. */
static void test_second_coupler_refused(void **state)
{
    (void)state;
    child c;
    start_participant(&c, 1.0);
    proto_peer *a = open_peer(c.endpoint), *b = open_peer(c.endpoint);
    proto_message reply;
    memset(&reply, 0, sizeof reply);
    nc_error err;
    if (proto_peer_hello(a, &reply, &err)) fail_msg("%s", err.message);
    run_step(a, 0, &reply);

    /* B's hello: refused, one coupler per participant */
    assert_int_equal(proto_peer_hello(b, &reply, &err), -1);
    assert_int_equal(err.code, PROTO_ERR_PEER);
    assert_non_null(strstr(err.message, "one coupler per participant"));

    /* B goes on regardless (no version agreed: it sends version-1 commands without a token) */
    assert_int_equal(send_command(b, PROTO_MSG_BEGIN_STEP, 1, 0, 1e-3, NULL, &reply, &err), -1);
    assert_int_equal(err.code, PROTO_ERR_PEER);
    assert_non_null(strstr(err.message, "another coupler"));

    /* a raw coupler with another token in version 2 */
    raw r;
    raw_open(&r, ZMQ_REQ, c.endpoint, 0);
    char text[2048];
    raw_request(&r, "{\"type\":\"begin_step\",\"version\":2,\"session\":\"feedfacefeedface\","
                "\"step\":1,\"dt\":0.001}", NULL, 0, &reply, text, sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_ERROR);
    assert_non_null(strstr(reply.text, "from another coupler"));
    assert_non_null(strstr(reply.text, "feedfacefeedface"));
    raw_close(&r);

    /* A's run continues: its next step and shutdown succeed */
    run_step(a, 1, &reply);
    shutdown_peer(a, &reply);
    proto_message_free(&reply);
    proto_peer_close(a);
    proto_peer_close(b);
    proto_serve_summary sum;
    assert_int_equal(finish_participant(&c, &sum), 0);
    assert_int_equal(sum.steps_accepted, 2);
    assert_int_equal(sum.failed, 0);
    assert_int_equal(sum.rejected, 0);
    /* B's hello, B's begin_step and the raw coupler's begin_step */
    assert_int_equal(sum.refused, 3);
}

/* A version-2 command before any hello is refused (PROTO_ERR_SESSION, counted in refused)
 * with a reason naming the missing hello; after a hello the same coupler is served. */
static void test_version_2_before_hello_refused(void **state)
{
    (void)state;
    child c;
    start_participant(&c, 1.0);
    raw r;
    raw_open(&r, ZMQ_REQ, c.endpoint, 0);
    proto_message reply;
    memset(&reply, 0, sizeof reply);
    char text[2048];
    const char *s = "\"session\":\"0123456789abcdef\"";
    char h[512];
    snprintf(h, sizeof h, "{\"type\":\"begin_step\",\"version\":2,%s,\"step\":0,\"dt\":0.001}", s);
    raw_request(&r, h, NULL, 0, &reply, text, sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_ERROR);
    assert_int_equal(reply.retryable, 0);
    assert_non_null(strstr(reply.text, "refused begin_step: no hello yet"));
    /* the same connection, after hello: served */
    snprintf(h, sizeof h, "{\"type\":\"hello\",\"version\":1,\"versions\":[1,2],%s}", s);
    raw_request(&r, h, NULL, 0, &reply, text, sizeof text);
    assert_int_equal(reply.version, 2);
    snprintf(h, sizeof h, "{\"type\":\"begin_step\",\"version\":2,%s,\"step\":0,\"dt\":0.001}", s);
    raw_request(&r, h, NULL, 0, &reply, text, sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_BEGIN_STEP);
    assert_string_equal(reply.session, "0123456789abcdef");
    snprintf(h, sizeof h, "{\"type\":\"shutdown\",\"version\":2,%s}", s);
    raw_request(&r, h, NULL, 0, &reply, text, sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_SHUTDOWN);
    raw_close(&r);
    proto_message_free(&reply);
    proto_serve_summary sum;
    assert_int_equal(finish_participant(&c, &sum), 0);
    assert_int_equal(sum.refused, 1);
    assert_int_equal(sum.failed, 0);
    assert_int_equal(sum.rejected, 0);
    assert_int_equal(sum.commands, 2);   /* the refused one is not dispatched */
}

/* ---- (d) stale replies ----------------------------------------------------------------- */

typedef enum {
    STALE_STEP,          /* the reply answers another step */
    STALE_ITERATION,     /* ... another iteration */
    STALE_SESSION,       /* ... another coupler's session */
    STALE_NOT_REPLY,     /* "reply": false */
    STALE_NO_REPLY_FIELD,/* no "reply" at all */
    STALE_TYPE,          /* another type */
    STALE_NONE,          /* a correct reply */
    STALE_COUNT
} stale_kind;

/* Child: a raw REP participant; hello is answered correctly (version 2, the session echoed),
 * then the i-th SOLVE gets the defect i of stale_kind. Exit 0 when all were answered. */
static int stale_child(int endpoint_fd)
{
    raw r;
    raw_open(&r, ZMQ_REP, "tcp://127.0.0.1:*", 1);
    char bound[256];
    size_t size = sizeof bound;
    zmq_getsockopt(r.socket, ZMQ_LAST_ENDPOINT, bound, &size);
    if (write(endpoint_fd, bound, strlen(bound) + 1) < 0) return 2;
    close(endpoint_fd);
    proto_message cmd;
    memset(&cmd, 0, sizeof cmd);
    nc_error err;
    int rc = 0;
    for (int i = -1; i < STALE_COUNT; i++) {
        if (raw_receive(&r, &cmd, NULL, 0, &err)) { rc = 3; break; }
        char h[1024];
        long step = cmd.step;
        int iteration = cmd.iteration;
        const char *type = proto_type_name(cmd.type), *session = cmd.session, *reply = "true";
        char reply_field[32];
        if (i == STALE_STEP) step++;
        if (i == STALE_ITERATION) iteration++;
        if (i == STALE_SESSION) session = "ffffffffffffffff";
        if (i == STALE_NOT_REPLY) reply = "false";
        if (i == STALE_TYPE) type = "begin_step";
        snprintf(reply_field, sizeof reply_field, "\"reply\":%s,", reply);
        snprintf(h, sizeof h, "{\"type\":\"%s\",\"version\":2,%s\"step\":%ld,\"iteration\":%d,"
                 "\"session\":\"%s\",\"role\":\"fem\",\"text\":\"restore\"}", type,
                 i == STALE_NO_REPLY_FIELD ? "" : reply_field, step, iteration, session);
        zmq_send(r.socket, h, strlen(h), 0);
    }
    proto_message_free(&cmd);
    raw_close(&r);
    return rc;
}

static void test_stale_replies_caught(void **state)
{
    (void)state;
    int ep[2];
    assert_int_equal(pipe(ep), 0);
    pid_t pid = fork();
    if (pid == 0) {
        close(ep[0]);
        _exit(stale_child(ep[1]));
    }
    close(ep[1]);
    char endpoint[256];
    ssize_t got = read(ep[0], endpoint, sizeof endpoint - 1);
    assert_true(got > 0);
    endpoint[got] = '\0';
    close(ep[0]);

    proto_peer *peer = open_peer(endpoint);
    proto_message reply;
    memset(&reply, 0, sizeof reply);
    nc_error err;
    if (proto_peer_hello(peer, &reply, &err)) fail_msg("%s", err.message);
    assert_int_equal(proto_peer_version(peer), 2);
    char token[PROTO_NAME_MAX];
    snprintf(token, sizeof token, "%s", proto_peer_session(peer));
    char expect[STALE_COUNT][160];
    snprintf(expect[STALE_STEP], sizeof expect[0], "answers step 6, iteration 2 (a stale reply?)");
    snprintf(expect[STALE_ITERATION], sizeof expect[0], "answers step 5, iteration 3 (a stale reply?)");
    snprintf(expect[STALE_SESSION], sizeof expect[0], "session 'ffffffffffffffff' instead of %s", token);
    snprintf(expect[STALE_NOT_REPLY], sizeof expect[0], "not marked as a reply");
    snprintf(expect[STALE_NO_REPLY_FIELD], sizeof expect[0], "not marked as a reply");
    snprintf(expect[STALE_TYPE], sizeof expect[0], "answered solve (step 5, iteration 2, t = 0.05 s) with 'begin_step'");
    double force[N_NODES * 3] = {0};
    for (int i = 0; i < STALE_COUNT; i++) {
        int rc = send_command(peer, PROTO_MSG_SOLVE, 5, 2, 1e-3, force, &reply, &err);
        if (i == STALE_NONE) {
            if (rc) fail_msg("correct reply refused: %s", err.message);
            continue;
        }
        if (rc != -1 || err.code != PROTO_ERR_DECODE || !strstr(err.message, expect[i]))
            fail_msg("defect %d: rc %d, code %d, message '%s' (expected '%s')", i, rc, err.code,
                     err.message, expect[i]);
        assert_non_null(strstr(err.message, "participant 'fem'"));
    }
    proto_message_free(&reply);
    proto_peer_close(peer);
    int status = 0;
    waitpid(pid, &status, 0);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 0);
}

/* ---- (e) retryable failures ------------------------------------------------------------ */

/* The child's solve fails with PROTO_ERR_STEP_FAILED above dt = 1 ms (as fem_solver's Newton
 * does): the coupler gets PROTO_ERR_STEP_FAILED with the reason, retries the step with half
 * the step and succeeds; a solve without its force array fails for good (PROTO_ERR_PEER).
 * The participant counts the first in `retryable`, the second in `failed`. */
static void test_retryable_failure(void **state)
{
    (void)state;
    child c;
    start_participant(&c, 1e-3);
    proto_peer *peer = open_peer(c.endpoint);
    proto_message reply;
    memset(&reply, 0, sizeof reply);
    nc_error err;
    if (proto_peer_hello(peer, &reply, &err)) fail_msg("%s", err.message);
    double force[N_NODES * 3];
    for (int i = 0; i < N_NODES * 3; i++) force[i] = -5e4;
    assert_int_equal(send_command(peer, PROTO_MSG_BEGIN_STEP, 0, 0, 2e-3, NULL, &reply, &err), 0);
    assert_int_equal(send_command(peer, PROTO_MSG_SOLVE, 0, 1, 2e-3, force, &reply, &err), -1);
    assert_int_equal(err.code, PROTO_ERR_STEP_FAILED);
    assert_non_null(strstr(err.message, "Newton did not converge in 25 iterations at dt = 0.002 s"));
    assert_non_null(strstr(err.message, "solve (step 0, iteration 1)"));
    /* the step again with half the step size */
    assert_int_equal(send_command(peer, PROTO_MSG_BEGIN_STEP, 0, 0, 1e-3, NULL, &reply, &err), 0);
    if (send_command(peer, PROTO_MSG_SOLVE, 0, 1, 1e-3, force, &reply, &err))
        fail_msg("%s", err.message);
    const double *u;
    assert_int_equal(proto_message_get_f64(&reply, "displacement", N_NODES, 3, &u, NULL, &err), 0);
    assert_near(u[0], -5e4 / 1e6, 1e-18);
    /* a failure no smaller step cures */
    assert_int_equal(send_command(peer, PROTO_MSG_SOLVE, 0, 2, 1e-3, NULL, &reply, &err), -1);
    assert_int_equal(err.code, PROTO_ERR_PEER);
    assert_non_null(strstr(err.message, "'force'"));
    if (send_command(peer, PROTO_MSG_SOLVE, 0, 3, 1e-3, force, &reply, &err))
        fail_msg("%s", err.message);
    assert_int_equal(send_command(peer, PROTO_MSG_ACCEPT_STEP, 0, 0, 1e-3, NULL, &reply, &err), 0);
    shutdown_peer(peer, &reply);
    proto_message_free(&reply);
    proto_peer_close(peer);
    proto_serve_summary sum;
    assert_int_equal(finish_participant(&c, &sum), 0);
    assert_int_equal(sum.retryable, 1);
    assert_int_equal(sum.failed, 1);
    assert_int_equal(sum.refused, 0);
    assert_int_equal(sum.steps_accepted, 1);
    assert_int_equal(sum.solves, 4);
}

/* A raw coupler sees the flag on the wire: "retryable": true in the error reply. */
static void test_retryable_flag_on_the_wire(void **state)
{
    (void)state;
    child c;
    start_participant(&c, 1e-3);
    raw r;
    raw_open(&r, ZMQ_REQ, c.endpoint, 0);
    proto_message reply;
    memset(&reply, 0, sizeof reply);
    char text[2048];
    const char *s = "\"session\":\"1111222233334444\"";
    char h[512];
    snprintf(h, sizeof h, "{\"type\":\"hello\",\"version\":1,\"versions\":[1,2],%s}", s);
    raw_request(&r, h, NULL, 0, &reply, text, sizeof text);
    snprintf(h, sizeof h, "{\"type\":\"begin_step\",\"version\":2,%s,\"step\":0,\"dt\":0.01}", s);
    raw_request(&r, h, NULL, 0, &reply, text, sizeof text);
    snprintf(h, sizeof h, "{\"type\":\"solve\",\"version\":2,%s,\"step\":0,\"iteration\":1,"
             "\"dt\":0.01}", s);
    raw_request(&r, h, NULL, 0, &reply, text, sizeof text);
    assert_int_equal(reply.type, PROTO_MSG_ERROR);
    assert_int_equal(reply.retryable, 1);
    assert_non_null(strstr(text, "\"retryable\":true"));
    assert_int_equal(reply.step, 0);
    assert_int_equal(reply.iteration, 1);
    assert_string_equal(reply.session, "1111222233334444");
    snprintf(h, sizeof h, "{\"type\":\"shutdown\",\"version\":2,%s}", s);
    raw_request(&r, h, NULL, 0, &reply, text, sizeof text);
    raw_close(&r);
    proto_message_free(&reply);
    proto_serve_summary sum;
    assert_int_equal(finish_participant(&c, &sum), 0);
    assert_int_equal(sum.retryable, 1);
    assert_int_equal(sum.failed, 0);
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hello_negotiates_version_2),
        cmocka_unit_test(test_sessions_differ),
        cmocka_unit_test(test_version_1_coupler_served),
        cmocka_unit_test(test_second_coupler_refused),
        cmocka_unit_test(test_version_2_before_hello_refused),
        cmocka_unit_test(test_stale_replies_caught),
        cmocka_unit_test(test_retryable_failure),
        cmocka_unit_test(test_retryable_flag_on_the_wire),
    };
    return cmocka_run_group_tests_name("protocol version 2", tests, NULL, NULL);
}
