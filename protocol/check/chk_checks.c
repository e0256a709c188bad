/* chk_checks — the conformance checks of netcouple-check (chk_checks.h). */
#define _XOPEN_SOURCE 700 /* nftw */
#include "chk_checks.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <ftw.h>
#include <sys/stat.h>
#include <unistd.h>

#include "chk_interface.h"
#include "chk_process.h"
#include "chk_wire.h"

#define EXIT_WAIT_S 15.0   /* after shutdown: closing files may take a moment */
#define IDLE_MARGIN_S 10.0 /* the idle run: allowed beyond the idle time */
#define IDLE_RUN_S 1.0     /* --idle-timeout of the idle run */

typedef struct session {
    const chk_config *cfg;
    chk_report *rep;
    const char *run;            /* "clean", "error", "idle" */
    chk_wire wire;
    int wire_open;
    chk_process proc;
    int launched;
    char dir[PATH_MAX];
    char log[PATH_MAX];
    char token[PROTO_NAME_MAX]; /* this coupler's session */
    int version;                /* agreed in hello */
    char role[PROTO_NAME_MAX];  /* the role checked */
    char caps[PROTO_TEXT_MAX];
    int dead;                   /* stopped answering: no more requests */
    char dead_why[600];
    int errors_seen;            /* error replies that are errors of the run (not refusals) */
    chk_interface *iface;
    double *input[2];           /* the solve input: fem force; dem displacement, velocity */
    proto_message reply;
} session;

static int is_fem(const session *s) { return strcmp(s->role, "fem") == 0; }

/* ---- transport helpers ------------------------------------------------------------------ */

static void mark_dead(session *s, const char *what, const nc_error *e)
{
    s->dead = 1;
    char last[200] = "";
    if (s->launched && chk_process_wait(&s->proc, 0.3)) {
        chk_last_log_line(s->log, last, sizeof last);
        snprintf(s->dead_why, sizeof s->dead_why, "%s: the participant exited with status %d "
                 "(its last output: %s)", what, s->proc.status, last[0] ? last : "none");
    } else {
        snprintf(s->dead_why, sizeof s->dead_why, "%s: %s", what, e->message);
    }
}

static void header(session *s, proto_message *m)
{
    m->version = s->version ? s->version : PROTO_VERSION_MIN;
    snprintf(m->session, sizeof m->session, "%s", s->version >= 2 ? s->token : "");
}

/* Sends cmd in this session's version and token; 0 with the reply in s->reply. -1: no
 * usable reply (err says why); a timeout or transport failure ends the run. */
/* A request that got no usable reply: a malformed reply is named as such (the participant
 * still serves), anything else (timeout, closed connection) marks the participant dead. */
static int request_failed(session *s, const char *what, nc_error *err)
{
    if (err->code != PROTO_ERR_DECODE && err->code != PROTO_ERR_VERSION) {
        mark_dead(s, what, err);
        snprintf(err->message, sizeof err->message, "%s", s->dead_why);
    } else {
        nc_error_prefix(err, "malformed reply to %s", what);
    }
    return -1;
}

static int request(session *s, proto_message *cmd, int keep_header, nc_error *err)
{
    if (s->dead) return nc_error_set(err, 1, "%s", s->dead_why);
    if (!keep_header) header(s, cmd);
    char what[96];
    snprintf(what, sizeof what, "%s (step %ld, iteration %d)", proto_type_name(cmd->type),
             cmd->step, cmd->iteration);
    if (chk_wire_request(&s->wire, cmd, &s->reply, err)) return request_failed(s, what, err);
    return 0;
}

static int request_raw(session *s, const void *const *frames, const size_t *lengths, size_t n,
                       const char *what, nc_error *err)
{
    if (s->dead) return nc_error_set(err, 1, "%s", s->dead_why);
    if (chk_wire_send_raw(&s->wire, frames, lengths, n, err) ||
        chk_wire_receive(&s->wire, &s->reply, err))
        return request_failed(s, what, err);
    return 0;
}

static void command(proto_message *m, proto_msg_type type, long step, int iteration,
                    double time_s, double dt_s)
{
    memset(m, 0, sizeof *m);
    proto_message_init(m, type);
    m->step = step;
    m->iteration = iteration;
    m->time_s = time_s;
    m->dt_s = dt_s;
}

/* Whether reply answers cmd (§2.2): a reply, of its type or an error, in the agreed version;
 * version 2: its session and (unless an error to an unread command) its step and iteration.
 * Returns 1 and leaves `why` empty when it does. */
static int answers(const session *s, const proto_message *cmd, const proto_message *r,
                   int unread_ok, char *why, size_t size)
{
    why[0] = '\0';
    if (!r->is_reply) snprintf(why, size, "not marked as a reply (\"reply\": true)");
    else if (r->type != cmd->type && r->type != PROTO_MSG_ERROR)
        snprintf(why, size, "answered %s with '%s'", proto_type_name(cmd->type), proto_type_name(r->type));
    else if (s->version && r->version != s->version)
        snprintf(why, size, "reply of version %d after agreeing on %d", r->version, s->version);
    else if (s->version >= 2 && strcmp(r->session, s->token) != 0)
        snprintf(why, size, "reply carries session '%s' instead of '%s'", r->session, s->token);
    else if (s->version >= 2 &&
             !(unread_ok && r->type == PROTO_MSG_ERROR && r->step == -1 && r->iteration == 0) &&
             (r->step != cmd->step || r->iteration != cmd->iteration))
        snprintf(why, size, "reply answers step %ld, iteration %d instead of step %ld, iteration %d",
                 r->step, r->iteration, cmd->step, cmd->iteration);
    return why[0] == '\0';
}

/* A normal acknowledgement (or answer) of cmd: 0, else -1 with why. */
static int expect_ok(session *s, proto_message *cmd, char *why, size_t size)
{
    nc_error e;
    nc_error_clear(&e);
    if (request(s, cmd, 0, &e)) {
        snprintf(why, size, "%s", e.message);
        return -1;
    }
    if (!answers(s, cmd, &s->reply, 0, why, size)) return -1;
    if (s->reply.type == PROTO_MSG_ERROR) {
        s->errors_seen++;
        snprintf(why, size, "error reply: %s", s->reply.text);
        return -1;
    }
    return 0;
}

/* ---- inputs and outputs of solve ---------------------------------------------------------- */

static const char *output_names_fem[] = {"displacement", "velocity", NULL};
static const char *output_names_dem[] = {"force", NULL};

static const char **output_names(const session *s)
{
    return is_fem(s) ? output_names_fem : output_names_dem;
}

static int make_inputs(session *s, nc_error *err)
{
    size_t n = s->iface->n;
    for (int k = 0; k < 2; k++) {
        free(s->input[k]);
        s->input[k] = calloc(3 * n, sizeof(double));
        if (!s->input[k]) return nc_error_set(err, 1, "out of memory");
    }
    /* fem: a load on the central node pointing down (-z); dem: the net at rest */
    if (is_fem(s)) s->input[0][3 * chk_interface_central_node(s->iface) + 2] = -s->cfg->force_n;
    return 0;
}

static int add_inputs(session *s, proto_message *m, nc_error *err)
{
    size_t n = s->iface->n;
    if (is_fem(s)) return proto_message_add_f64(m, "force", s->input[0], n, 3, err);
    if (proto_message_add_f64(m, "displacement", s->input[0], n, 3, err) ||
        proto_message_add_f64(m, "velocity", s->input[1], n, 3, err))
        return -1;
    return 0;
}

/* The answer's arrays, checked for shape and copied one after the other into *out. */
static int take_answer(session *s, double **out, char *why, size_t size)
{
    const char **names = output_names(s);
    size_t n = s->iface->n, count = 0;
    for (int k = 0; names[k]; k++) count += 3 * n;
    double *copy = malloc(count * sizeof *copy);
    if (!copy) {
        snprintf(why, size, "out of memory");
        return -1;
    }
    size_t at = 0;
    for (int k = 0; names[k]; k++) {
        const double *data;
        nc_error e;
        nc_error_clear(&e);
        if (proto_message_get_f64(&s->reply, names[k], n, 3, &data, NULL, &e)) {
            snprintf(why, size, "%s", e.message);
            free(copy);
            return -1;
        }
        memcpy(copy + at, data, 3 * n * sizeof *data);
        at += 3 * n;
    }
    *out = copy;
    return 0;
}

/* solve (step, iteration) with the standard input: 0 with the answer copied into *out. */
static int solve(session *s, long step, int iteration, double **out, char *why, size_t size)
{
    proto_message cmd;
    command(&cmd, PROTO_MSG_SOLVE, step, iteration, (double)step * s->cfg->dt_s, s->cfg->dt_s);
    nc_error e;
    nc_error_clear(&e);
    if (add_inputs(s, &cmd, &e)) {
        snprintf(why, size, "%s", e.message);
        return -1;
    }
    if (expect_ok(s, &cmd, why, size)) return -1;
    return take_answer(s, out, why, size);
}

static int step_command(session *s, proto_msg_type type, long step, char *why, size_t size)
{
    proto_message cmd;
    command(&cmd, type, step, 0, (double)step * s->cfg->dt_s, s->cfg->dt_s);
    return expect_ok(s, &cmd, why, size);
}

static size_t count_differences(const double *a, const double *b, size_t count, size_t *first)
{
    size_t d = 0;
    for (size_t i = 0; i < count; i++)
        if (memcmp(&a[i], &b[i], sizeof a[i]) != 0) {
            if (!d) *first = i;
            d++;
        }
    return d;
}

static double max_abs(const double *a, size_t count)
{
    double m = 0;
    for (size_t i = 0; i < count; i++) m = fmax(m, fabs(a[i]));
    return m;
}

/* "velocity[4][2]" for entry i of the concatenated answer */
static void entry_name(const session *s, size_t i, char *out, size_t size)
{
    size_t per = 3 * s->iface->n;
    snprintf(out, size, "%s[%zu][%zu]", output_names(s)[i / per], (i % per) / 3, i % 3);
}

/* ---- starting and ending a run ------------------------------------------------------------- */

static int make_dir(const char *path, nc_error *err)
{
    if (mkdir(path, 0755) != 0 && errno != EEXIST)
        return nc_error_set(err, 1, "%s: cannot create: %s", path, strerror(errno));
    return 0;
}

/* Starts the program (launch mode) or connects (endpoint mode). Rows: "<run>: start" when it
 * fails; in the clean run "endpoint file" always. */
static int start(session *s, const char *base, double idle_s, int report_endpoint)
{
    const chk_config *c = s->cfg;
    char name[CHK_NAME_MAX];
    nc_error e;
    nc_error_clear(&e);
    const char *endpoint = c->endpoint;
    char line[512];
    if (c->program) {
        snprintf(s->dir, sizeof s->dir, "%s/%s", base, s->run);
        snprintf(s->log, sizeof s->log, "%s/participant.log", s->dir);
        char endpoint_file[PATH_MAX + 32], idle[32];
        snprintf(endpoint_file, sizeof endpoint_file, "%s/participant.endpoint", s->dir);
        snprintf(idle, sizeof idle, "%g", idle_s);
        if (make_dir(s->dir, &e)) goto failed;
        unlink(endpoint_file);
        size_t argc = 0;
        while (c->program[argc]) argc++;
        char **argv = calloc(argc + 10, sizeof *argv);
        if (!argv) { nc_error_set(&e, 1, "out of memory"); goto failed; }
        memcpy(argv, c->program, argc * sizeof *argv);
        size_t k = argc;
        argv[k++] = "--endpoint";
        argv[k++] = "tcp://127.0.0.1:*";
        argv[k++] = "--endpoint-file";
        argv[k++] = endpoint_file;
        argv[k++] = "--output";
        argv[k++] = s->dir;
        argv[k++] = "--idle-timeout";
        argv[k++] = idle;
        argv[k] = NULL;
        int rc = chk_process_start(&s->proc, argv, s->log, &e);
        free(argv);
        if (rc) goto failed;
        s->launched = 1;
        if (chk_wait_endpoint_file(&s->proc, endpoint_file, c->start_timeout_s, line, sizeof line, &e)) {
            char last[200];
            chk_last_log_line(s->log, last, sizeof last);
            size_t used = strlen(e.message);
            if (last[0])
                snprintf(e.message + used, sizeof e.message - used, " (its last output: %.200s)", last);
            goto failed;
        }
        /* a launcher hands the line to the coupler as it is: a concrete ZeroMQ address */
        int concrete = (strncmp(line, "tcp://", 6) == 0 && !strchr(line, '*') &&
                        strrchr(line, ':') > line + 5) || strncmp(line, "ipc://", 6) == 0;
        if (!concrete) {
            if (report_endpoint)
                chk_report_add(s->rep, "endpoint file", CHK_FAIL, "'%s' is not a bound address "
                               "(expected e.g. tcp://127.0.0.1:40311, §7)", line);
            s->dead = 1;
            snprintf(s->dead_why, sizeof s->dead_why, "no usable endpoint");
            return -1;
        }
        if (report_endpoint)
            chk_report_add(s->rep, "endpoint file", CHK_PASS, "%s, %.2f s after the start", line,
                           chk_now_s() - s->proc.started_s);
        endpoint = line;
    }
    if (chk_wire_open(&s->wire, endpoint, c->timeout_s, &e)) goto failed;
    s->wire_open = 1;
    return 0;
failed:
    snprintf(name, sizeof name, report_endpoint ? "endpoint file" : "%s run: start", s->run);
    chk_report_add(s->rep, name, CHK_FAIL, "%s", e.message);
    s->dead = 1;
    snprintf(s->dead_why, sizeof s->dead_why, "%s", e.message);
    return -1;
}

static void finish(session *s)
{
    if (s->wire_open) chk_wire_close(&s->wire);
    s->wire_open = 0;
    if (s->launched) chk_process_stop(&s->proc, 3.0);
    proto_message_free(&s->reply);
    free(s->input[0]);
    free(s->input[1]);
    s->input[0] = s->input[1] = NULL;
}

/* ---- hello and interface ----------------------------------------------------------------- */

static void make_token(char *out, size_t size, unsigned salt)
{
    unsigned long long x = 0;
    FILE *f = fopen("/dev/urandom", "rb");
    if (!f || fread(&x, sizeof x, 1, f) != 1) x = (unsigned long long)getpid() * 2654435761u;
    if (f) fclose(f);
    snprintf(out, size, "%016llx", x ^ salt);
}

static void send_hello(proto_message *m, const char *token)
{
    command(m, PROTO_MSG_HELLO, -1, 0, 0, 0);
    m->version = PROTO_VERSION_MIN;  /* readable by a version-1 participant (§8) */
    m->offered_version = PROTO_VERSION;
    snprintf(m->session, sizeof m->session, "%s", token);
    snprintf(m->role, sizeof m->role, "coupler");
    snprintf(m->name, sizeof m->name, "netcouple-check");
}

/* hello; with `rows` one row per property, else a row only when it fails. */
static int hello(session *s, int rows, double idle_s)
{
    char why[600], name[CHK_NAME_MAX];
    snprintf(name, sizeof name, "%s run: hello", s->run);
    make_token(s->token, sizeof s->token, 1);
    proto_message cmd;
    send_hello(&cmd, s->token);
    nc_error e;
    nc_error_clear(&e);
    if (request(s, &cmd, 1, &e)) {
        chk_report_add(s->rep, rows ? "hello" : name, CHK_FAIL, "%s", e.message);
        return -1;
    }
    const proto_message *r = &s->reply;
    if (!r->is_reply || r->type != PROTO_MSG_HELLO) {
        chk_report_add(s->rep, rows ? "hello" : name, CHK_FAIL, "%s",
                       r->type == PROTO_MSG_ERROR ? r->text : "the reply is not a hello reply");
        s->dead = 1;
        snprintf(s->dead_why, sizeof s->dead_why, "no handshake");
        return -1;
    }
    int version_ok = r->version >= PROTO_VERSION_MIN && r->version <= PROTO_VERSION;
    int session_ok = r->version < 2 || strcmp(r->session, s->token) == 0;
    const char *want = s->cfg->role;
    int role_ok = want ? strcmp(r->role, want) == 0 : (!strcmp(r->role, "fem") || !strcmp(r->role, "dem"));
    snprintf(s->caps, sizeof s->caps, "%s", r->text);
    snprintf(s->role, sizeof s->role, "%s", want ? want : r->role);
    int has_idle = proto_message_has_value(r, "idle_timeout_s");
    double idle = proto_message_value(r, "idle_timeout_s", -1);
    int idle_ok = has_idle && (!s->launched || fabs(idle - idle_s) < 1e-6);
    s->version = version_ok ? r->version : 0;
    if (rows) {
        chk_report_add(s->rep, "hello: version", version_ok ? CHK_PASS : CHK_FAIL,
                       version_ok ? "%d agreed (offered %d to %d); participant '%s'"
                                  : "%d: not one of the versions offered (%d to %d); participant '%s'",
                       r->version, PROTO_VERSION_MIN, PROTO_VERSION, r->name);
        if (r->version < 2)
            chk_report_add(s->rep, "hello: session echoed", CHK_SKIP, "version 1 has no session");
        else
            chk_report_add(s->rep, "hello: session echoed", session_ok ? CHK_PASS : CHK_FAIL,
                           session_ok ? "%s" : "'%s' instead of the token sent", r->session);
        chk_report_add(s->rep, "hello: role", role_ok ? CHK_PASS : CHK_FAIL,
                       role_ok ? "'%s'" : want ? "'%s', expected the role given by --role"
                                               : "'%s': neither fem nor dem (give --role)", r->role);
        if (!r->text[0])
            chk_report_add(s->rep, "hello: capabilities", CHK_WARN, "none announced: no restore, "
                           "so only weak coupling will run with this participant");
        else
            chk_report_add(s->rep, "hello: capabilities", CHK_PASS, "%s", r->text);
        if (!has_idle)
            chk_report_add(s->rep, "hello: idle_timeout_s", CHK_FAIL, "the value is missing: the "
                           "coupler cannot check its reply timeout against it (§6)");
        else if (!idle_ok)
            chk_report_add(s->rep, "hello: idle_timeout_s", CHK_FAIL, "%g s although started with "
                           "--idle-timeout %g", idle, idle_s);
        else
            chk_report_add(s->rep, "hello: idle_timeout_s", CHK_PASS, "%g s%s", idle,
                           s->launched ? " (as passed with --idle-timeout)" : "");
    } else if (!version_ok || !session_ok || !role_ok) {
        snprintf(why, sizeof why, "version %d, session '%s', role '%s'", r->version, r->session, r->role);
        chk_report_add(s->rep, name, CHK_FAIL, "%s", why);
    }
    if (!version_ok || !session_ok || !role_ok) {
        s->dead = 1;
        snprintf(s->dead_why, sizeof s->dead_why, "no valid handshake");
        return -1;
    }
    return 0;
}

/* v2: a second coupler's hello is refused and the session goes on (§3.2). */
static void second_hello(session *s)
{
    const char *row = "session: second coupler's hello";
    if (s->version < 2) {
        chk_report_add(s->rep, row, CHK_SKIP, "version 1 has no session");
        return;
    }
    char other[PROTO_NAME_MAX];
    make_token(other, sizeof other, 0x5a5a5a5au);
    proto_message cmd;
    send_hello(&cmd, other);
    nc_error e;
    nc_error_clear(&e);
    if (request(s, &cmd, 1, &e)) {
        chk_report_add(s->rep, row, CHK_FAIL, "%s", e.message);
        return;
    }
    if (s->reply.type != PROTO_MSG_ERROR) {
        chk_report_add(s->rep, row, CHK_FAIL, "accepted (a second coupler took over the "
                       "participant; one coupler per participant, §3.2)");
        /* the participant may now serve the other token: follow it, so later rows still run */
        snprintf(s->token, sizeof s->token, "%s", other);
        return;
    }
    char text[200];
    snprintf(text, sizeof text, "%s", s->reply.text);
    if (strcmp(s->reply.session, s->token) == 0)
        chk_report_add(s->rep, row, CHK_FAIL, "refused, but the refusal carries this coupler's "
                       "session instead of the hello's own (§2.2): %s", text);
    else
        chk_report_add(s->rep, row, CHK_PASS, "refused: %s", text);
}

/* interface: the FEM's is read and checked; the DEM gets s->iface. */
static int interface(session *s, int rows)
{
    char why[600], name[CHK_NAME_MAX];
    snprintf(name, sizeof name, rows ? "interface" : "%s run: interface", s->run);
    proto_message cmd;
    command(&cmd, PROTO_MSG_INTERFACE, -1, 0, 0, 0);
    nc_error e;
    nc_error_clear(&e);
    if (!is_fem(s) && chk_interface_add(s->iface, &cmd, &e)) {
        chk_report_add(s->rep, name, CHK_FAIL, "%s", e.message);
        return -1;
    }
    if (expect_ok(s, &cmd, why, sizeof why)) {
        chk_report_add(s->rep, name, CHK_FAIL, "%s", why);
        return -1;
    }
    if (is_fem(s)) {
        chk_interface got;
        memset(&got, 0, sizeof got);
        if (chk_interface_from_reply(&got, &s->reply, &e)) {
            chk_report_add(s->rep, name, CHK_FAIL, "%s", e.message);
            return -1;
        }
        if (s->iface->n && (got.n != s->iface->n || got.m != s->iface->m ||
                            memcmp(got.coords, s->iface->coords, 3 * got.n * sizeof(double)) ||
                            memcmp(got.node_ids, s->iface->node_ids, got.n * sizeof(int32_t)))) {
            chk_report_add(s->rep, name, CHK_FAIL, "differs from the interface of the clean run "
                           "(same input, another start)");
            chk_interface_free(&got);
            return -1;
        }
        chk_interface_free(s->iface);
        *s->iface = got;
        if (rows)
            chk_report_add(s->rep, name, CHK_PASS, "%zu nodes, %zu elements; node_ids [n], "
                           "coordinates [n, 3], elements [m, 2] consistent", got.n, got.m);
    } else if (rows) {
        chk_report_add(s->rep, name, CHK_PASS, "accepted the %zu-node, %zu-element interface",
                       s->iface->n, s->iface->m);
    }
    nc_error_clear(&e);
    if (make_inputs(s, &e)) {
        chk_report_add(s->rep, name, CHK_FAIL, "%s", e.message);
        return -1;
    }
    return 0;
}

/* ---- the clean run: steps and restore ------------------------------------------------------ */

static void solve_values(session *s)
{
    static const char *fem[] = {"newton_iterations", "residual_norm", NULL};
    static const char *dem[] = {"near_interface", "min_gap_m", "contacts", "substeps", NULL};
    const char **names = is_fem(s) ? fem : dem;
    char missing[200] = "";
    for (int k = 0; names[k]; k++)
        if (!proto_message_has_value(&s->reply, names[k]))
            snprintf(missing + strlen(missing), sizeof missing - strlen(missing), "%s%s",
                     missing[0] ? ", " : "", names[k]);
    if (missing[0])
        chk_report_add(s->rep, "solve: values", CHK_WARN, "missing %s (§3; the coupler "
                       "reports less without them)", missing);
    else
        chk_report_add(s->rep, "solve: values", CHK_PASS, "%zu values", s->reply.n_values);
}

static void compare(session *s, const char *row, const double *a, const double *b, size_t count,
                    int restore, int nonzero, const char *what)
{
    size_t first = 0, d = count_differences(a, b, count, &first);
    if (!nonzero) {
        chk_report_add(s->rep, row, restore ? CHK_WARN : CHK_SKIP, "the answer is all zeros: "
                       "nothing to compare (choose an input that moves the participant: --force, "
                       "or a particle touching the interface)");
        return;
    }
    if (!restore) {
        chk_report_add(s->rep, row, CHK_SKIP, "'restore' not announced: strong coupling "
                       "refuses this participant (%s: %s)", what,
                       d ? "the answers differ" : "the answers are identical");
        return;
    }
    if (d == 0) {
        chk_report_add(s->rep, row, CHK_PASS, "%s: %zu values bit-identical", what, count);
        return;
    }
    char entry[96];
    entry_name(s, first, entry, sizeof entry);
    chk_report_add(s->rep, row, CHK_FAIL, "%s: %zu of %zu values differ, first %s: %.17g vs "
                   "%.17g (does not restore its start-of-step state, or its answer depends "
                   "on where an iteration started: protocol/README.md §3 solve; strong "
                   "coupling will refuse it)", what, d, count, entry, a[first], b[first]);
}

static void clean_steps(session *s)
{
    char why[600];
    double dt = s->cfg->dt_s;
    int restore = proto_has_capability(s->caps, "restore");
    size_t count = 3 * s->iface->n * (is_fem(s) ? 2 : 1);
    double *first = NULL, *again = NULL, *rebegun = NULL;
    if (step_command(s, PROTO_MSG_BEGIN_STEP, 0, why, sizeof why)) {
        chk_report_add(s->rep, "begin_step", CHK_FAIL, "%s", why);
        return;
    }
    chk_report_add(s->rep, "begin_step", CHK_PASS, "step 0, t = 0 s, dt = %g s acknowledged", dt);
    if (solve(s, 0, 1, &first, why, sizeof why)) {
        chk_report_add(s->rep, "solve", CHK_FAIL, "%s", why);
        return;
    }
    double size = max_abs(first, count);
    chk_report_add(s->rep, "solve", CHK_PASS, "step 0, iteration 1: %s [n, 3] answered, "
                   "max |value| %.3g", is_fem(s) ? "displacement, velocity" : "force", size);
    solve_values(s);
    int nonzero = size > 0;
    if (!nonzero)
        chk_report_add(s->rep, "solve: non-zero answer", CHK_WARN, "all zeros: the restore "
                       "checks below cannot tell restoring from not restoring");
    if (solve(s, 0, 2, &again, why, sizeof why))
        chk_report_add(s->rep, "restore: solve repeated", CHK_FAIL, "%s", why);
    else
        compare(s, "restore: solve repeated", first, again, count, restore, nonzero,
                "iteration 2 with the input of iteration 1");
    if (step_command(s, PROTO_MSG_BEGIN_STEP, 0, why, sizeof why) ||
        solve(s, 0, 1, &rebegun, why, sizeof why))
        chk_report_add(s->rep, "restore: step begun again", CHK_FAIL, "%s", why);
    else
        compare(s, "restore: step begun again", first, rebegun, count, restore, nonzero,
                "begin_step 0 again, then iteration 1");
    if (step_command(s, PROTO_MSG_ACCEPT_STEP, 0, why, sizeof why))
        chk_report_add(s->rep, "accept_step", CHK_FAIL, "%s", why);
    else
        chk_report_add(s->rep, "accept_step", CHK_PASS, "step 0 committed");
    free(again);
    again = NULL;
    double *next = NULL;
    if (step_command(s, PROTO_MSG_BEGIN_STEP, 1, why, sizeof why) ||
        solve(s, 1, 1, &next, why, sizeof why) || solve(s, 1, 2, &again, why, sizeof why) ||
        step_command(s, PROTO_MSG_ACCEPT_STEP, 1, why, sizeof why)) {
        chk_report_add(s->rep, "next step", CHK_FAIL, "step 1: %s", why);
    } else {
        size_t at = 0;
        size_t d = count_differences(next, again, count, &at);
        if (restore && d)
            chk_report_add(s->rep, "next step", CHK_FAIL, "step 1: the repeated solve differs in "
                           "%zu values (the start-of-step state of step 1 is not restored)", d);
        else
            chk_report_add(s->rep, "next step", CHK_PASS, "step 1 begun, solved twice%s, accepted",
                           restore ? " (identical)" : "");
    }
    free(first);
    free(again);
    free(rebegun);
    free(next);
}

/* v2: a command of another session is refused and this session is undisturbed (§3.2). */
static void foreign_command(session *s)
{
    const char *row = "session: foreign command";
    if (s->version < 2) {
        chk_report_add(s->rep, row, CHK_SKIP, "version 1 has no session");
        return;
    }
    proto_message cmd;
    command(&cmd, PROTO_MSG_BEGIN_STEP, 2, 0, 2 * s->cfg->dt_s, s->cfg->dt_s);
    header(s, &cmd);
    make_token(cmd.session, sizeof cmd.session, 0xa5a5a5a5u);
    nc_error e;
    nc_error_clear(&e);
    if (request(s, &cmd, 1, &e)) {
        chk_report_add(s->rep, row, CHK_FAIL, "%s", e.message);
        return;
    }
    if (s->reply.type != PROTO_MSG_ERROR) {
        chk_report_add(s->rep, row, CHK_FAIL, "begin_step of session '%s' was accepted (§3.2: "
                       "refused, \"from another coupler\")", cmd.session);
        return;
    }
    char text[200], carried[PROTO_NAME_MAX];
    snprintf(text, sizeof text, "%s", s->reply.text);
    snprintf(carried, sizeof carried, "%s", s->reply.session);
    int own = strcmp(s->reply.session, cmd.session) == 0;
    /* the session goes on: this coupler's hello (allowed in every state) is answered */
    proto_message again;
    send_hello(&again, s->token);
    nc_error_clear(&e);
    int served = request(s, &again, 1, &e) == 0 && s->reply.type == PROTO_MSG_HELLO &&
                 s->reply.version == s->version;
    if (!served) {
        chk_report_add(s->rep, row, CHK_FAIL, "refused, but then this coupler's own hello was "
                       "not answered with its session's version: %s",
                       e.message[0] ? e.message : s->reply.text);
        return;
    }
    if (!own)
        chk_report_add(s->rep, row, CHK_FAIL, "refused and the session goes on, but the refusal "
                       "carries session '%s' instead of the command's own (§2.2): %s",
                       carried, text);
    else
        chk_report_add(s->rep, row, CHK_PASS, "refused, the session goes on: %s", text);
}

/* shutdown, then the exit status the spec gives (§6). */
static void shutdown_and_exit(session *s, const char *row_shutdown, const char *row_exit,
                              int expected)
{
    char why[600];
    if (step_command(s, PROTO_MSG_SHUTDOWN, -1, why, sizeof why)) {
        chk_report_add(s->rep, row_shutdown, CHK_FAIL, "%s", why);
        return;
    }
    chk_report_add(s->rep, row_shutdown, CHK_PASS, "acknowledged");
    if (!s->launched) {
        chk_report_add(s->rep, row_exit, CHK_SKIP, "not started by netcouple-check");
        return;
    }
    double t0 = chk_now_s();
    if (!chk_process_wait(&s->proc, EXIT_WAIT_S)) {
        chk_report_add(s->rep, row_exit, CHK_FAIL, "still running %.0f s after shutdown",
                       EXIT_WAIT_S);
        return;
    }
    char last[200];
    chk_last_log_line(s->log, last, sizeof last);
    chk_report_add(s->rep, row_exit, s->proc.status == expected ? CHK_PASS : CHK_FAIL,
                   "%d after %.2f s (expected %d, §6)%s%s", s->proc.status, chk_now_s() - t0,
                   expected, last[0] && s->proc.status != expected ? "; its last output: " : "",
                   s->proc.status != expected ? last : "");
}

/* ---- the error run -------------------------------------------------------------------------- */

/* The header fields of a received message (its arrays are not kept). */
static proto_message head_of(const proto_message *m)
{
    proto_message h = *m;
    for (int k = 0; k < PROTO_MAX_ARRAYS; k++) {
        h.storage[k] = NULL;
        h.storage_capacity[k] = 0;
    }
    h.n_arrays = 0;
    return h;
}

/* The reply to a provoked error: an error reply answering the command (unread commands:
 * step -1 allowed), then the participant still serving (the next valid command answered). */
static void judge_error(session *s, const char *row, const proto_message *cmd,
                        const proto_message *reply, int unread_ok, const char *next_what,
                        int next_ok, const char *next_why, chk_verdict if_accepted)
{
    char why[600];
    if (!answers(s, cmd, reply, unread_ok, why, sizeof why)) {
        chk_report_add(s->rep, row, CHK_FAIL, "%s", why);
        return;
    }
    if (reply->type != PROTO_MSG_ERROR) {
        chk_report_add(s->rep, row, if_accepted, "answered normally instead of with an error "
                       "reply%s", if_accepted == CHK_WARN ? " (§3.2; the coupler never sends "
                       "it, so runs are not affected)" : "");
        return;
    }
    s->errors_seen++;
    if (!next_ok)
        chk_report_add(s->rep, row, CHK_FAIL, "error reply, but then %s failed: %s", next_what,
                       next_why);
    else if (!reply->text[0])
        chk_report_add(s->rep, row, CHK_WARN, "error reply without a reason in 'text'; still serving");
    else
        chk_report_add(s->rep, row, CHK_PASS, "%.200s; still serving", reply->text);
}

/* The valid solve that shows the participant still serves. */
static int still_serving(session *s, long step, int *iteration, char *why, size_t size)
{
    double *answer = NULL;
    int rc = solve(s, step, ++*iteration, &answer, why, size);
    free(answer);
    return rc == 0;
}

/* Sends cmd (raw frames when given), judges the reply, then a valid solve. */
static void provoked(session *s, const char *row, proto_message *cmd, const void *const *frames,
                     const size_t *lengths, size_t n_frames, int unread_ok, long step,
                     int *iteration, chk_verdict if_accepted)
{
    nc_error e;
    nc_error_clear(&e);
    int failed = frames ? request_raw(s, frames, lengths, n_frames, row, &e)
                        : request(s, cmd, 0, &e);
    if (failed) {
        chk_report_add(s->rep, row, CHK_FAIL, "%s", e.message);
        return;
    }
    proto_message reply = head_of(&s->reply), sent = head_of(cmd);
    char why[600] = "";
    int ok = still_serving(s, step, iteration, why, sizeof why);
    judge_error(s, row, &sent, &reply, unread_ok, "a valid solve", ok, why, if_accepted);
}

static void error_steps(session *s)
{
    char why[600];
    double dt = s->cfg->dt_s;
    size_t n = s->iface->n;
    long step = 0;
    int it = 0;
    nc_error e;
    proto_message cmd;

    /* out of order (§3.2): a participant must refuse these */
    {
        const char *row = "order: solve before begin_step";
        command(&cmd, PROTO_MSG_SOLVE, step, ++it, 0, dt);
        nc_error_clear(&e);
        if (add_inputs(s, &cmd, &e) || request(s, &cmd, 0, &e)) {
            chk_report_add(s->rep, row, CHK_FAIL, "%s", e.message);
            return;
        }
        proto_message reply = head_of(&s->reply), sent = head_of(&cmd);
        int ok = step_command(s, PROTO_MSG_BEGIN_STEP, step, why, sizeof why) == 0;
        judge_error(s, row, &sent, &reply, 0, "begin_step", ok, why, CHK_FAIL);
    }
    if (s->dead) return;
    command(&cmd, PROTO_MSG_ACCEPT_STEP, step, 0, 0, dt);
    provoked(s, "order: accept_step without solve", &cmd, NULL, NULL, 0, 0, step, &it, CHK_FAIL);

    /* malformed commands (§2.2): each answered with an error, the next solve served */
    static const struct { const char *row, *format; } texts[] = {
        {"malformed: bad JSON", "{\"type\": \"solve\", \"version\": %d, \"session\": \"%s\", "
                                "\"step\": %ld, \"iteration\": %d, \"arrays\": ["},
        {"malformed: unknown type", "{\"type\": \"frobnicate\", \"version\": %d, \"session\": "
                                    "\"%s\", \"step\": %ld, \"iteration\": %d}"},
        {"malformed: not a JSON object", "[\"solve\", %d, \"%s\", %ld, %d]"},
        {"malformed: unknown version", "{\"type\": \"solve\", \"version\": %d, \"session\": "
                                       "\"%s\", \"step\": %ld, \"iteration\": %d}"},
    };
    for (size_t k = 0; k < sizeof texts / sizeof texts[0] && !s->dead; k++) {
        char json[512];
        command(&cmd, PROTO_MSG_SOLVE, step, ++it, 0, dt);
        header(s, &cmd);
        int version = strstr(texts[k].row, "version") ? 99 : cmd.version;
        snprintf(json, sizeof json, texts[k].format, version, cmd.session, step, it);
        const void *frames[1] = {json};
        size_t lengths[1] = {strlen(json)};
        provoked(s, texts[k].row, &cmd, frames, lengths, 1, 1, step, &it, CHK_FAIL);
    }
    double *bad = calloc(3 * n, sizeof *bad);
    if (!bad) return;
    if (!s->dead) {   /* NaN in the first input array */
        memcpy(bad, s->input[0], 3 * n * sizeof *bad);
        bad[3 * chk_interface_central_node(s->iface) + 2] = NAN;
        command(&cmd, PROTO_MSG_SOLVE, step, ++it, 0, dt);
        nc_error_clear(&e);
        if (is_fem(s)) proto_message_add_f64(&cmd, "force", bad, n, 3, &e);
        else {
            proto_message_add_f64(&cmd, "displacement", bad, n, 3, &e);
            proto_message_add_f64(&cmd, "velocity", s->input[1], n, 3, &e);
        }
        provoked(s, "malformed: NaN in an array", &cmd, NULL, NULL, 0, 1, step, &it, CHK_FAIL);
    }
    if (!s->dead) {   /* a frame 8 bytes shorter than its descriptor says */
        command(&cmd, PROTO_MSG_SOLVE, step, ++it, 0, dt);
        header(s, &cmd);
        nc_error_clear(&e);
        char *text = NULL;
        size_t text_length = 0;
        if (add_inputs(s, &cmd, &e) == 0 && proto_encode_header(&cmd, &text, &text_length, &e) == 0) {
            const void *frames[3];
            size_t lengths[3], k = 0;
            for (; k < cmd.n_arrays; k++) {
                frames[k] = cmd.arrays[k].data;
                lengths[k] = cmd.arrays[k].count * sizeof(double);
            }
            lengths[0] -= sizeof(double);
            frames[k] = text;
            lengths[k++] = text_length;
            provoked(s, "malformed: frame length", &cmd, frames, lengths, k, 1, step, &it, CHK_FAIL);
        }
        free(text);
    }
    if (!s->dead) {   /* well-formed, but [n, 2] where [n, 3] is required (the solver's check) */
        command(&cmd, PROTO_MSG_SOLVE, step, ++it, 0, dt);
        nc_error_clear(&e);
        if (is_fem(s)) proto_message_add_f64(&cmd, "force", s->input[0], n, 2, &e);
        else {
            proto_message_add_f64(&cmd, "displacement", s->input[0], n, 2, &e);
            proto_message_add_f64(&cmd, "velocity", s->input[1], n, 2, &e);
        }
        provoked(s, "malformed: wrong array shape", &cmd, NULL, NULL, 0, 1, step, &it, CHK_FAIL);
    }
    if (!s->dead) {
        command(&cmd, PROTO_MSG_SOLVE, step, ++it, 0, dt);
        provoked(s, "malformed: missing array", &cmd, NULL, NULL, 0, 1, step, &it, CHK_FAIL);
    }
    free(bad);
    if (s->dead) return;
    if (step_command(s, PROTO_MSG_ACCEPT_STEP, step, why, sizeof why))
        chk_report_add(s->rep, "error run: accept_step", CHK_FAIL, "after the errors: %s", why);
}

/* ---- the idle run --------------------------------------------------------------------------- */

static void idle_run(session *s, const char *base)
{
    const char *row = "idle timeout";
    if (start(s, base, IDLE_RUN_S, 0)) return;
    double t0 = chk_now_s();
    if (!chk_process_wait(&s->proc, IDLE_RUN_S + IDLE_MARGIN_S)) {
        chk_report_add(s->rep, row, CHK_FAIL, "started with --idle-timeout %g, no command sent: "
                       "still running after %.0f s", IDLE_RUN_S, IDLE_RUN_S + IDLE_MARGIN_S);
        return;
    }
    double took = chk_now_s() - t0;
    char last[200];
    chk_last_log_line(s->log, last, sizeof last);
    chk_report_add(s->rep, row, s->proc.status == 1 ? CHK_PASS : CHK_FAIL,
                   "--idle-timeout %g, no command: exit status %d after %.1f s (expected 1, §6)%s%s",
                   IDLE_RUN_S, s->proc.status, took, last[0] ? "; " : "", last);
}

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st;
    (void)flag;
    (void)ftw;
    return remove(path);
}

/* Removes a run folder of the harness's own making. */
static void remove_tree(const char *path)
{
    nftw(path, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

/* ---- checkpoint/resume (capability `checkpoint`, §3.3) --------------------------------------- */

static void session_init(session *s, const chk_config *cfg, chk_report *rep, chk_interface *f,
                         const char *run);

static int named_command(session *s, proto_msg_type type, long step, const char *name,
                         char *why, size_t size)
{
    proto_message cmd;
    command(&cmd, type, step, 0, (double)step * s->cfg->dt_s, 0.0);
    snprintf(cmd.text, sizeof cmd.text, "%s", name);
    return expect_ok(s, &cmd, why, size);
}

/* Step 0 accepted, CHECKPOINT, step 1 solved (answer A), shut down; the participant started
 * again in the same folder: hello, interface, RESUME, step 1 solved with the same input:
 * the answer must be A bit for bit. */
static void checkpoint_runs(const chk_config *cfg, chk_report *rep, chk_interface *f,
                            const char *base, const char *role)
{
    const char *row = "checkpoint/resume bit-identity", *name = "chk_000001";
    char why[600] = "";
    double *a = NULL, *b = NULL, *scratch = NULL;
    session s;
    session_init(&s, cfg, rep, f, "checkpoint");
    snprintf(s.role, sizeof s.role, "%s", role);
    int ok = start(&s, base, cfg->idle_timeout_s, 0) == 0 && hello(&s, 0, cfg->idle_timeout_s) == 0 &&
             interface(&s, 0) == 0;
    if (ok && (step_command(&s, PROTO_MSG_BEGIN_STEP, 0, why, sizeof why) ||
               solve(&s, 0, 1, &scratch, why, sizeof why) ||
               step_command(&s, PROTO_MSG_ACCEPT_STEP, 0, why, sizeof why))) {
        ok = 0;
        chk_report_add(rep, row, CHK_FAIL, "step 0: %s", why);
    } else if (ok && named_command(&s, PROTO_MSG_CHECKPOINT, 1, name, why, sizeof why)) {
        ok = 0;
        chk_report_add(rep, row, CHK_FAIL, "checkpoint after step 0: %s", why);
    } else if (ok && (step_command(&s, PROTO_MSG_BEGIN_STEP, 1, why, sizeof why) ||
                      solve(&s, 1, 1, &a, why, sizeof why) ||
                      step_command(&s, PROTO_MSG_ACCEPT_STEP, 1, why, sizeof why) ||
                      step_command(&s, PROTO_MSG_SHUTDOWN, -1, why, sizeof why))) {
        ok = 0;
        chk_report_add(rep, row, CHK_FAIL, "step 1 after the checkpoint: %s", why);
    }
    if (ok && !chk_process_wait(&s.proc, EXIT_WAIT_S)) {
        ok = 0;
        chk_report_add(rep, row, CHK_FAIL, "still running %.0f s after shutdown", EXIT_WAIT_S);
    }
    if (!ok && s.dead && why[0] == '\0') chk_report_add(rep, row, CHK_FAIL, "%s", s.dead_why);
    finish(&s);
    if (ok) {
        session_init(&s, cfg, rep, f, "checkpoint");   /* the same folder */
        snprintf(s.role, sizeof s.role, "%s", role);
        ok = start(&s, base, cfg->idle_timeout_s, 0) == 0 &&
             hello(&s, 0, cfg->idle_timeout_s) == 0 && interface(&s, 0) == 0;
        if (!ok) {
            chk_report_add(rep, row, CHK_FAIL, "restarted participant: %s", s.dead_why);
        } else if (named_command(&s, PROTO_MSG_RESUME, 1, name, why, sizeof why) ||
                   step_command(&s, PROTO_MSG_BEGIN_STEP, 1, why, sizeof why) ||
                   solve(&s, 1, 1, &b, why, sizeof why)) {
            chk_report_add(rep, row, CHK_FAIL, "resume %s, step 1: %s", name, why);
        } else {
            size_t count = 3 * s.iface->n * (is_fem(&s) ? 2 : 1), at = 0;
            size_t d = count_differences(a, b, count, &at);
            if (d)
                chk_report_add(rep, row, CHK_FAIL, "step 1 after resume differs from step 1 "
                               "after the checkpoint in %zu of %zu values (first: entry %zu, "
                               "%.17g vs %.17g)", d, count, at, b[at], a[at]);
            else
                chk_report_add(rep, row, CHK_PASS, "checkpoint after step 0, restart, resume: "
                               "step 1 answered identically (%zu values)", count);
            step_command(&s, PROTO_MSG_ACCEPT_STEP, 1, why, sizeof why);
            step_command(&s, PROTO_MSG_SHUTDOWN, -1, why, sizeof why);
            chk_process_wait(&s.proc, EXIT_WAIT_S);
        }
        finish(&s);
    }
    free(a);
    free(b);
    free(scratch);
}

/* ---- all runs -------------------------------------------------------------------------------- */

static void session_init(session *s, const chk_config *cfg, chk_report *rep, chk_interface *f,
                         const char *run)
{
    memset(s, 0, sizeof *s);
    s->cfg = cfg;
    s->rep = rep;
    s->iface = f;
    s->run = run;
}

int chk_run(const chk_config *cfg, chk_report *rep, nc_error *err)
{
    chk_interface f;
    memset(&f, 0, sizeof f);
    if (cfg->interface_file ? chk_interface_read(&f, cfg->interface_file, err)
                            : chk_interface_synthetic(&f, err))
        return -1;
    char base[PATH_MAX] = "";
    int temporary = 0;
    if (cfg->program) {
        if (cfg->work_dir) {
            snprintf(base, sizeof base, "%s", cfg->work_dir);
            if (make_dir(base, err)) { chk_interface_free(&f); return -1; }
        } else {
            const char *tmp = getenv("TMPDIR");
            snprintf(base, sizeof base, "%s/netcouple-check.XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
            if (!mkdtemp(base)) {
                chk_interface_free(&f);
                return nc_error_set(err, 1, "%s: cannot create a run folder: %s", base, strerror(errno));
            }
            temporary = 1;
        }
    }
    /* the DEM's interface comes from the harness; the FEM's replaces it */
    if (cfg->role && strcmp(cfg->role, "fem") == 0) chk_interface_free(&f);

    session s;
    session_init(&s, cfg, rep, &f, "clean");
    int ok = start(&s, base, cfg->idle_timeout_s, 1) == 0 && hello(&s, 1, cfg->idle_timeout_s) == 0;
    if (ok && is_fem(&s) && f.n) chk_interface_free(&f);   /* role learnt from hello */
    if (ok) second_hello(&s);
    ok = ok && interface(&s, 1) == 0;
    if (ok && is_fem(&s) && cfg->save_interface) {
        nc_error e;
        nc_error_clear(&e);
        if (chk_interface_write(&f, cfg->save_interface, &e))
            chk_report_add(rep, "interface: saved", CHK_FAIL, "%s", e.message);
    }
    if (ok) clean_steps(&s);
    if (ok) foreign_command(&s);
    if (s.dead)
        chk_report_add(rep, "clean run", CHK_FAIL, "not finished: the checks after the FAIL "
                       "above were not run");
    else if (cfg->program)
        shutdown_and_exit(&s, "shutdown", "exit status: clean run", 0);
    char role[PROTO_NAME_MAX];
    snprintf(role, sizeof role, "%s", s.role);
    const int can_checkpoint = s.version >= 2 && proto_has_capability(s.caps, "checkpoint");

    if (cfg->program) {
        finish(&s);
        session_init(&s, cfg, rep, &f, "error");
        ok = start(&s, base, cfg->idle_timeout_s, 0) == 0 && hello(&s, 0, cfg->idle_timeout_s) == 0 &&
             interface(&s, 0) == 0;
    } else {
        ok = ok && !s.dead;
    }
    if (ok) error_steps(&s);
    if (s.dead)
        chk_report_add(rep, "error run", CHK_FAIL, "not finished: the checks after the FAIL "
                       "above were not run");
    else
        shutdown_and_exit(&s, cfg->program ? "shutdown after errors" : "shutdown",
                          "exit status: after errors", s.errors_seen ? 1 : 0);
    finish(&s);

    if (cfg->program && can_checkpoint)
        checkpoint_runs(cfg, rep, &f, base, role);
    else
        chk_report_add(rep, "checkpoint/resume bit-identity", CHK_SKIP,
                       cfg->program ? "capability 'checkpoint' not announced"
                                    : "not started by netcouple-check (it restarts the participant)");

    if (cfg->program && cfg->idle_check) {
        session_init(&s, cfg, rep, &f, "idle");
        snprintf(s.role, sizeof s.role, "%s", role);
        idle_run(&s, base);
        finish(&s);
    } else {
        chk_report_add(rep, "idle timeout", CHK_SKIP, cfg->program ? "--no-idle-check"
                       : "not started by netcouple-check");
    }
    chk_interface_free(&f);
    if (temporary) {
        if (rep->n_failed == 0) remove_tree(base);
        else fprintf(stderr, "netcouple-check: the participant's logs are in %s\n", base);
    }
    return 0;
}
