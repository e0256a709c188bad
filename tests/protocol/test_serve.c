/* Tests of the participant serve loop (proto_serve.h): a fake participant whose handlers
 * record their calls serves in a thread of this process; the test drives it as the coupler
 * through a proto_peer (and a raw ZeroMQ socket for garbage). Checked: restore_state exactly
 * on the repeated SOLVEs of a step; SOLVE / ACCEPT_STEP outside a begun step refused while
 * serving continues; a failing handler answered with an error naming command, step and
 * iteration; CHECKPOINT only between steps and RESUME only once before the first step;
 * SHUTDOWN ends the loop with 0; the idle timeout and the stop flag end it. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <zmq.h>

#include "proto_serve.h"

/* ---- the fake participant ------------------------------------------------------------- */

typedef struct fake {
    char calls[4096];          /* "save 0; solve 0.1; restore 1.2; ..." */
    long fail_solve_step;      /* solve fails at this step and iteration (-1: never) */
    int fail_solve_iteration;
    long fail_save_step;       /* save_state fails at this step (-1: never) */
    int n_reports;
    char reports[8][PROTO_TEXT_MAX];
    double value;              /* returned by solve as "echo" */
} fake;

static void record(fake *f, const char *format, ...)
{
    size_t used = strlen(f->calls);
    va_list args;
    va_start(args, format);
    vsnprintf(f->calls + used, sizeof f->calls - used, format, args);
    va_end(args);
}

static int f_interface(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    (void)cmd;
    (void)reply;
    (void)err;
    record(ctx, "interface; ");
    return 0;
}

static int f_save(void *ctx, const proto_message *cmd, nc_error *err)
{
    fake *f = ctx;
    record(f, "save %ld; ", cmd->step);
    if (cmd->step == f->fail_save_step) return nc_error_set(err, 1, "fake save failure");
    return 0;
}

static int f_restore(void *ctx, const proto_message *cmd, nc_error *err)
{
    (void)err;
    record(ctx, "restore %ld.%d; ", cmd->step, cmd->iteration);
    return 0;
}

static int f_solve(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    fake *f = ctx;
    record(f, "solve %ld.%d; ", cmd->step, cmd->iteration);
    if (cmd->step == f->fail_solve_step && cmd->iteration == f->fail_solve_iteration)
        return nc_error_set(err, 1, "fake Newton failure");
    f->value = 10.0 * (double)cmd->step + cmd->iteration;
    return proto_message_set_value(reply, "echo", f->value, err);
}

static int f_accept(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    (void)reply;
    (void)err;
    record(ctx, "accept %ld; ", cmd->step);
    return 0;
}

static int f_shutdown(void *ctx, const proto_message *cmd, nc_error *err)
{
    (void)cmd;
    (void)err;
    record(ctx, "shutdown; ");
    return 0;
}

static int f_checkpoint(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    (void)reply;
    (void)err;
    record(ctx, "checkpoint %ld %s; ", cmd->step, cmd->text);
    return 0;
}

static int f_resume(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    (void)reply;
    (void)err;
    record(ctx, "resume %ld %s; ", cmd->step, cmd->text);
    return 0;
}

static void f_report(void *ctx, const char *message)
{
    fake *f = ctx;
    if (f->n_reports < 8) snprintf(f->reports[f->n_reports], PROTO_TEXT_MAX, "%s", message);
    f->n_reports++;
}

static const proto_serve_handlers fake_handlers = {
    .interface = f_interface, .save_state = f_save, .restore_state = f_restore,
    .solve = f_solve, .accept_step = f_accept, .shutdown = f_shutdown, .report = f_report,
    .checkpoint = f_checkpoint, .resume = f_resume};

/* ---- the serving thread and the coupler side ------------------------------------------ */

typedef struct server {
    proto_participant *p;
    fake f;
    volatile sig_atomic_t stop;
    pthread_t thread;
    int rc;
    proto_serve_summary sum;
    nc_error err;
} server;

static void *serve_thread(void *arg)
{
    server *s = arg;
    s->rc = proto_serve(s->p, &fake_handlers, &s->f, &s->stop, &s->sum, &s->err);
    return NULL;
}

static void start(server *s, int idle_timeout_ms)
{
    memset(s, 0, sizeof *s);
    s->f.fail_solve_step = -1;
    s->f.fail_save_step = -1;
    proto_options options;
    proto_options_default(&options);
    options.idle_timeout_ms = idle_timeout_ms;
    nc_error err;
    if (proto_participant_open(&s->p, "tcp://127.0.0.1:*", "fem", "fake", "restore", &options, &err))
        fail_msg("%s", err.message);
    nc_error_clear(&s->err);
}

static void run(server *s)
{
    assert_int_equal(pthread_create(&s->thread, NULL, serve_thread, s), 0);
}

static void finish(server *s)
{
    assert_int_equal(pthread_join(s->thread, NULL), 0);
    proto_participant_close(s->p);
}

typedef struct coupler {
    proto_peer *peer;
    proto_message req, rep;
    nc_error err;
    char text[64];             /* the next command's text (a checkpoint name) */
} coupler;

static void connect_coupler(coupler *c, const server *s)
{
    memset(c, 0, sizeof *c);
    proto_options options;
    proto_options_default(&options);
    options.timeout_ms = 10000;
    if (proto_peer_open(&c->peer, "fake", proto_participant_endpoint(s->p), &options, &c->err) ||
        proto_peer_hello(c->peer, &c->rep, &c->err))
        fail_msg("%s", c->err.message);
    assert_string_equal(c->rep.role, "fem");
}

static void disconnect_coupler(coupler *c)
{
    proto_message_free(&c->req);
    proto_message_free(&c->rep);
    proto_peer_close(c->peer);
}

/* Sends one command; returns the proto_peer_request result (error text in c->err). */
static int command(coupler *c, proto_msg_type type, long step, int iteration)
{
    proto_message_init(&c->req, type);
    c->req.step = step;
    c->req.iteration = iteration;
    c->req.time_s = 0.01 * (double)(step > 0 ? step : 0);
    c->req.dt_s = 0.01;
    snprintf(c->req.text, sizeof c->req.text, "%s", c->text);
    nc_error_clear(&c->err);
    return proto_peer_request(c->peer, &c->req, &c->rep, &c->err);
}

static void ok(coupler *c, proto_msg_type type, long step, int iteration)
{
    if (command(c, type, step, iteration))
        fail_msg("%s step %ld iteration %d: %s", proto_type_name(type), step, iteration, c->err.message);
}

/* The command must be answered with an error reply containing both texts. */
static void refused(coupler *c, proto_msg_type type, long step, int iteration, const char *what,
                    const char *why)
{
    assert_int_equal(command(c, type, step, iteration), -1);
    assert_int_equal(c->err.code, PROTO_ERR_PEER);
    if (!strstr(c->err.message, what) || !strstr(c->err.message, why))
        fail_msg("error reply '%s' should name '%s' and '%s'", c->err.message, what, why);
}

/* ---- tests ---------------------------------------------------------------------------- */

static void test_restore_exactly_on_repeated_solves(void **state)
{
    (void)state;
    server s;
    start(&s, 10000);
    run(&s);
    coupler c;
    connect_coupler(&c, &s);
    ok(&c, PROTO_MSG_INTERFACE, -1, 0);
    /* weak step: one SOLVE, no restore */
    ok(&c, PROTO_MSG_BEGIN_STEP, 0, 0);
    ok(&c, PROTO_MSG_SOLVE, 0, 1);
    assert_true(proto_message_value(&c.rep, "echo", -1) == 1.0);
    ok(&c, PROTO_MSG_ACCEPT_STEP, 0, 0);
    /* strong step: three iterations, restore before the second and third */
    ok(&c, PROTO_MSG_BEGIN_STEP, 1, 0);
    for (int k = 1; k <= 3; k++) ok(&c, PROTO_MSG_SOLVE, 1, k);
    ok(&c, PROTO_MSG_ACCEPT_STEP, 1, 0);
    /* a participant first solved at iteration 2 (the coupler skipped it in iteration 1)
     * runs from the saved state: the rule counts SOLVEs, not iteration numbers */
    ok(&c, PROTO_MSG_BEGIN_STEP, 2, 0);
    ok(&c, PROTO_MSG_SOLVE, 2, 2);
    ok(&c, PROTO_MSG_SOLVE, 2, 3);
    ok(&c, PROTO_MSG_ACCEPT_STEP, 2, 0);
    /* a step begun again before it was accepted starts from the last accepted state */
    ok(&c, PROTO_MSG_BEGIN_STEP, 3, 0);
    ok(&c, PROTO_MSG_SOLVE, 3, 1);
    ok(&c, PROTO_MSG_BEGIN_STEP, 3, 0);
    ok(&c, PROTO_MSG_SOLVE, 3, 1);
    ok(&c, PROTO_MSG_ACCEPT_STEP, 3, 0);
    ok(&c, PROTO_MSG_SHUTDOWN, -1, 0);
    finish(&s);
    disconnect_coupler(&c);
    assert_int_equal(s.rc, 0);
    assert_string_equal(s.f.calls,
                        "interface; "
                        "save 0; solve 0.1; accept 0; "
                        "save 1; solve 1.1; restore 1.2; solve 1.2; restore 1.3; solve 1.3; accept 1; "
                        "save 2; solve 2.2; restore 2.3; solve 2.3; accept 2; "
                        "save 3; solve 3.1; restore 3.0; save 3; solve 3.1; accept 3; "
                        "shutdown; ");
    assert_int_equal(s.sum.commands, 19);
    assert_int_equal(s.sum.solves, 8);
    assert_int_equal(s.sum.restores, 4);
    assert_int_equal(s.sum.steps_accepted, 4);
    assert_int_equal(s.sum.failed, 0);
    assert_int_equal(s.sum.rejected, 0);
    assert_int_equal(s.sum.step_open, 0);
    assert_int_equal(s.f.n_reports, 0);
}

static void test_out_of_order_refused_and_serving_continues(void **state)
{
    (void)state;
    server s;
    start(&s, 10000);
    run(&s);
    coupler c;
    connect_coupler(&c, &s);
    refused(&c, PROTO_MSG_SOLVE, 0, 1, "solve (step 0, iteration 1)", "BEGIN_STEP must come first");
    refused(&c, PROTO_MSG_ACCEPT_STEP, 0, 0, "accept_step (step 0)", "BEGIN_STEP must come first");
    ok(&c, PROTO_MSG_BEGIN_STEP, 0, 0);
    refused(&c, PROTO_MSG_ACCEPT_STEP, 0, 0, "accept_step (step 0)", "no successful SOLVE");
    ok(&c, PROTO_MSG_SOLVE, 0, 1);
    ok(&c, PROTO_MSG_ACCEPT_STEP, 0, 0);
    /* the step is closed: neither a further SOLVE nor a second ACCEPT_STEP */
    refused(&c, PROTO_MSG_SOLVE, 0, 2, "solve (step 0, iteration 2)", "BEGIN_STEP must come first");
    refused(&c, PROTO_MSG_ACCEPT_STEP, 0, 0, "accept_step (step 0)", "BEGIN_STEP must come first");
    ok(&c, PROTO_MSG_SHUTDOWN, -1, 0);
    finish(&s);
    disconnect_coupler(&c);
    assert_int_equal(s.rc, 0);   /* SHUTDOWN: 0; the failures are in the summary */
    assert_string_equal(s.f.calls, "save 0; solve 0.1; accept 0; shutdown; ");
    assert_int_equal(s.sum.failed, 5);
    assert_int_equal(s.f.n_reports, 5);
    assert_non_null(strstr(s.f.reports[0], "solve (step 0, iteration 1): refused"));
}

static void test_checkpoint_between_steps_resume_once_first(void **state)
{
    (void)state;
    server s;
    start(&s, 10000);
    run(&s);
    coupler c;
    connect_coupler(&c, &s);
    refused(&c, PROTO_MSG_RESUME, 3, 0, "resume (step 3", "has no name");
    snprintf(c.text, sizeof c.text, "step_000003");
    ok(&c, PROTO_MSG_RESUME, 3, 0);
    refused(&c, PROTO_MSG_RESUME, 3, 0, "resume (step 3", "before the first begin_step, once");
    ok(&c, PROTO_MSG_BEGIN_STEP, 3, 0);
    refused(&c, PROTO_MSG_CHECKPOINT, 3, 0, "checkpoint (step 3", "a step is open");
    ok(&c, PROTO_MSG_SOLVE, 3, 1);
    ok(&c, PROTO_MSG_ACCEPT_STEP, 3, 0);
    snprintf(c.text, sizeof c.text, "step_000004");
    ok(&c, PROTO_MSG_CHECKPOINT, 4, 0);
    ok(&c, PROTO_MSG_SHUTDOWN, -1, 0);
    finish(&s);
    disconnect_coupler(&c);
    assert_int_equal(s.rc, 0);
    assert_string_equal(s.f.calls, "resume 3 step_000003; save 3; solve 3.1; accept 3; "
                                   "checkpoint 4 step_000004; shutdown; ");
    assert_int_equal(s.sum.checkpoints, 1);
    assert_int_equal(s.sum.resumed, 1);
    assert_int_equal(s.sum.failed, 3);
}

static void test_failing_handler_gets_error_reply(void **state)
{
    (void)state;
    server s;
    start(&s, 10000);
    s.f.fail_solve_step = 1;
    s.f.fail_solve_iteration = 1;
    s.f.fail_save_step = 2;
    run(&s);
    coupler c;
    connect_coupler(&c, &s);
    ok(&c, PROTO_MSG_BEGIN_STEP, 1, 0);
    refused(&c, PROTO_MSG_SOLVE, 1, 1, "solve (step 1, iteration 1)", "fake Newton failure");
    /* a failed SOLVE is not a result to accept */
    refused(&c, PROTO_MSG_ACCEPT_STEP, 1, 0, "accept_step (step 1)", "no successful SOLVE");
    /* the next SOLVE starts from the saved state again */
    ok(&c, PROTO_MSG_SOLVE, 1, 2);
    assert_true(proto_message_value(&c.rep, "echo", -1) == 12.0);
    ok(&c, PROTO_MSG_ACCEPT_STEP, 1, 0);
    /* a failed BEGIN_STEP begins no step */
    refused(&c, PROTO_MSG_BEGIN_STEP, 2, 0, "begin_step (step 2)", "fake save failure");
    refused(&c, PROTO_MSG_SOLVE, 2, 1, "solve (step 2, iteration 1)", "BEGIN_STEP must come first");
    ok(&c, PROTO_MSG_SHUTDOWN, -1, 0);
    finish(&s);
    disconnect_coupler(&c);
    assert_int_equal(s.rc, 0);
    assert_string_equal(s.f.calls, "save 1; solve 1.1; restore 1.2; solve 1.2; accept 1; save 2; shutdown; ");
    assert_int_equal(s.sum.failed, 4);
    assert_int_equal(s.sum.restores, 1);
    assert_string_equal(s.f.reports[0], "solve (step 1, iteration 1): fake Newton failure");
}

/* Malformed input is answered inside the receive and counted; the loop goes on. */
static void test_malformed_command_counted(void **state)
{
    (void)state;
    server s;
    start(&s, 10000);
    run(&s);
    void *context = zmq_ctx_new();
    void *socket = zmq_socket(context, ZMQ_REQ);
    assert_int_equal(zmq_connect(socket, proto_participant_endpoint(s.p)), 0);
    const char *bad = "not json at all";
    char buffer[2048] = {0};
    assert_true(zmq_send(socket, bad, strlen(bad), 0) > 0);
    assert_true(zmq_recv(socket, buffer, sizeof buffer - 1, 0) > 0);
    assert_non_null(strstr(buffer, "malformed command"));
    const char *shutdown = "{\"type\":\"shutdown\",\"version\":1}";
    assert_true(zmq_send(socket, shutdown, strlen(shutdown), 0) > 0);
    assert_true(zmq_recv(socket, buffer, sizeof buffer - 1, 0) > 0);
    zmq_close(socket);
    zmq_ctx_term(context);
    finish(&s);
    assert_int_equal(s.rc, 0);
    assert_int_equal(s.sum.rejected, 1);
    assert_int_equal(s.sum.failed, 0);
    assert_int_equal(s.f.n_reports, 1);
    assert_non_null(strstr(s.f.reports[0], "not valid JSON"));
}

static void test_shutdown_inside_a_step_reports_it(void **state)
{
    (void)state;
    server s;
    start(&s, 10000);
    run(&s);
    coupler c;
    connect_coupler(&c, &s);
    ok(&c, PROTO_MSG_BEGIN_STEP, 0, 0);
    ok(&c, PROTO_MSG_SOLVE, 0, 1);
    ok(&c, PROTO_MSG_SHUTDOWN, -1, 0);
    finish(&s);
    disconnect_coupler(&c);
    assert_int_equal(s.rc, 0);
    assert_int_equal(s.sum.step_open, 1);
    assert_int_equal(s.sum.step_solved, 1);   /* the participant's state is not the saved one */
}

static void test_idle_timeout_ends_with_its_error(void **state)
{
    (void)state;
    server s;
    start(&s, 200);
    serve_thread(&s);   /* nobody connects */
    proto_participant_close(s.p);
    assert_int_equal(s.rc, -1);
    assert_int_equal(s.err.code, PROTO_ERR_IDLE);
    assert_non_null(strstr(s.err.message, "idle timeout"));
    assert_int_equal(s.sum.commands, 0);
}

static void test_stop_flag_ends_with_1(void **state)
{
    (void)state;
    server s;
    start(&s, 10000);
    s.stop = 1;
    serve_thread(&s);
    proto_participant_close(s.p);
    assert_int_equal(s.rc, 1);
    assert_int_equal(s.sum.commands, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_restore_exactly_on_repeated_solves),
        cmocka_unit_test(test_out_of_order_refused_and_serving_continues),
        cmocka_unit_test(test_checkpoint_between_steps_resume_once_first),
        cmocka_unit_test(test_failing_handler_gets_error_reply),
        cmocka_unit_test(test_malformed_command_counted),
        cmocka_unit_test(test_shutdown_inside_a_step_reports_it),
        cmocka_unit_test(test_idle_timeout_ends_with_its_error),
        cmocka_unit_test(test_stop_flag_ends_with_1),
    };
    return cmocka_run_group_tests_name("protocol serve loop", tests, NULL, NULL);
}
