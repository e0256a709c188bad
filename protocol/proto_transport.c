/* proto_transport — the two ends of a coupling connection over ZeroMQ.
 *
 * The participant (a solver) binds a REP socket and answers one command at a time; the
 * coupler holds one REQ socket per participant (relaxed + correlated, so a request that
 * timed out does not wedge the socket). A socket monitor on the coupler side turns a peer
 * that closes its connection (process died) into an immediate error instead of a timeout.
 */
#include "proto.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <zmq.h>

#define RECEIVE_FRAMES_MAX (PROTO_MAX_ARRAYS + 1)
#define PEER_WAIT_SLICE_MS 100 /* how often a waiting coupler looks for a dead peer */

/* One receive buffer set: frames stay allocated between messages. */
typedef struct frame_buffer {
    zmq_msg_t frames[RECEIVE_FRAMES_MAX];
    int initialised;
} frame_buffer;

struct proto_participant {
    void *context;
    void *socket;
    char endpoint[256];
    char role[PROTO_NAME_MAX];
    char name[PROTO_NAME_MAX];
    char capabilities[PROTO_TEXT_MAX];
    proto_options options;
    int awaiting_reply;
    int version;                 /* agreed in hello; 0 before it */
    char session[PROTO_NAME_MAX];/* the coupler's token (version 2) */
    proto_message last_command;  /* header fields only (arrays are not kept) */
    proto_message hello_reply;
    frame_buffer buffer;
};

struct proto_peer {
    void *context;
    void *socket;
    void *monitor;
    int connected;        /* a connection to the peer is up (from the socket monitor) */
    int ever_connected;   /* it has been up once: losing it now means the peer went away */
    char name[PROTO_NAME_MAX];
    char endpoint[256];
    char last_sent[160];
    int pending;          /* a request was sent and its reply not yet received */
    proto_msg_type pending_type;   /* ... and what the reply must answer */
    long pending_step;
    int pending_iteration;
    int version;          /* agreed in hello; 0 before it */
    char session[PROTO_NAME_MAX];
    proto_options options;
    frame_buffer buffer;
};

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e3 * (double)ts.tv_sec + 1e-6 * (double)ts.tv_nsec;
}

void proto_options_default(proto_options *options)
{
    options->timeout_ms = PROTO_DEFAULT_TIMEOUT_MS;
    options->idle_timeout_ms = PROTO_DEFAULT_IDLE_TIMEOUT_MS;
    options->max_bytes = PROTO_DEFAULT_MAX_BYTES;
}

static void buffer_init(frame_buffer *b)
{
    for (int i = 0; i < RECEIVE_FRAMES_MAX; i++) zmq_msg_init(&b->frames[i]);
    b->initialised = 1;
}

static void buffer_close(frame_buffer *b)
{
    if (!b->initialised) return;
    for (int i = 0; i < RECEIVE_FRAMES_MAX; i++) zmq_msg_close(&b->frames[i]);
    b->initialised = 0;
}

static void describe(const proto_message *m, char *out, size_t size)
{
    if (m->type == PROTO_MSG_BEGIN_STEP || m->type == PROTO_MSG_SOLVE ||
        m->type == PROTO_MSG_ACCEPT_STEP || m->type == PROTO_MSG_CHECKPOINT ||
        m->type == PROTO_MSG_RESUME)
        snprintf(out, size, "%s (step %ld, iteration %d, t = %.6g s)", proto_type_name(m->type),
                 m->step, m->iteration, m->time_s);
    else
        snprintf(out, size, "%s", proto_type_name(m->type));
}

/* Sends the array frames, then the header as the last frame. Header last matters for speed:
 * ZeroMQ's encoder sends a large frame without copying only when its batch buffer is empty,
 * and a small header in front would push every array byte through that 8 KiB buffer. */
static int send_message(void *socket, const proto_message *m, const char *peer, nc_error *err)
{
    char *header = NULL;
    size_t header_length = 0;
    if (proto_encode_header(m, &header, &header_length, err)) return -1;
    int rc = 0;
    const uint16_t probe = 1;
    int little_endian = *(const uint8_t *)&probe == 1;
    for (size_t i = 0; i < m->n_arrays && rc >= 0; i++) {
        const proto_array *a = &m->arrays[i];
        size_t bytes = a->count * proto_dtype_size(a->dtype);
        if (little_endian) {
            rc = zmq_send(socket, a->data, bytes, ZMQ_SNDMORE);
        } else { /* big-endian host: the wire is little-endian */
            uint8_t *copy = malloc(bytes ? bytes : 1);
            if (!copy) {
                free(header);
                return nc_error_set(err, PROTO_ERR_TRANSPORT, "out of memory sending to %s", peer);
            }
            memcpy(copy, a->data, bytes);
            size_t item = proto_dtype_size(a->dtype);
            for (size_t k = 0; k < a->count; k++)
                for (size_t x = 0, y = item - 1; x < y; x++, y--) {
                    uint8_t t = copy[k * item + x];
                    copy[k * item + x] = copy[k * item + y];
                    copy[k * item + y] = t;
                }
            rc = zmq_send(socket, copy, bytes, ZMQ_SNDMORE);
            free(copy);
        }
    }
    if (rc >= 0) rc = zmq_send(socket, header, header_length, 0);
    free(header);
    if (rc >= 0) return 0;
    if (errno == EAGAIN)
        return nc_error_set(err, PROTO_ERR_TIMEOUT, "cannot send %s to %s: not reachable in time",
                            proto_type_name(m->type), peer);
    return nc_error_set(err, PROTO_ERR_TRANSPORT, "cannot send %s to %s: %s",
                        proto_type_name(m->type), peer, zmq_strerror(errno));
}

/* Receives one multipart message and decodes it; the arrays point into the received frames
 * (no copy) until the next receive on this endpoint. Waiting is bounded by the socket's
 * ZMQ_RCVTIMEO (a blocking receive costs less than zmq_poll in the hot path): returns 1 when
 * nothing arrived in that time, 0 on success, -1 on error. */
static int receive_message(void *socket, frame_buffer *b, proto_message *m, size_t max_bytes,
                           const char *peer, nc_error *err)
{
    size_t n = 0;
    int more = 1, too_many = 0;
    while (more) {
        zmq_msg_t *frame = &b->frames[n < RECEIVE_FRAMES_MAX ? n : RECEIVE_FRAMES_MAX - 1];
        if (zmq_msg_recv(frame, socket, 0) < 0) {
            if (n == 0 && errno == EAGAIN) return 1;
            if (errno == EINTR)
                return nc_error_set(err, PROTO_ERR_TRANSPORT, "interrupted while waiting for %s", peer);
            return nc_error_set(err, PROTO_ERR_TRANSPORT, "receiving from %s: %s", peer,
                                zmq_strerror(errno));
        }
        more = zmq_msg_more(frame);
        if (n < RECEIVE_FRAMES_MAX) n++;
        else too_many = 1; /* drain the rest so the socket stays in step */
    }
    if (too_many) {
        proto_message_init(m, PROTO_MSG_INVALID);
        return nc_error_set(err, PROTO_ERR_DECODE, "message from %s has more than %d frames", peer,
                            RECEIVE_FRAMES_MAX);
    }
    const void *frames[RECEIVE_FRAMES_MAX];
    size_t lengths[RECEIVE_FRAMES_MAX];
    for (size_t i = 0; i + 1 < n; i++) {
        frames[i] = zmq_msg_data(&b->frames[i]);
        lengths[i] = zmq_msg_size(&b->frames[i]);
    }
    return proto_decode_borrowed(m, zmq_msg_data(&b->frames[n - 1]), zmq_msg_size(&b->frames[n - 1]),
                                 frames, lengths, n - 1, max_bytes, err);
}

static void set_common_options(void *socket, const proto_options *options, int linger_ms)
{
    int64_t max = (int64_t)options->max_bytes;
    zmq_setsockopt(socket, ZMQ_MAXMSGSIZE, &max, sizeof max);
    zmq_setsockopt(socket, ZMQ_LINGER, &linger_ms, sizeof linger_ms);
}

/* ---- participant ----------------------------------------------------------------------- */

int proto_participant_open(proto_participant **out, const char *endpoint, const char *role,
                           const char *name, const char *capabilities,
                           const proto_options *options, nc_error *err)
{
    *out = NULL;
    proto_participant *p = calloc(1, sizeof *p);
    if (!p) return nc_error_set(err, PROTO_ERR_TRANSPORT, "out of memory");
    if (options) p->options = *options;
    else proto_options_default(&p->options);
    snprintf(p->role, sizeof p->role, "%s", role ? role : "participant");
    snprintf(p->name, sizeof p->name, "%s", name ? name : "");
    snprintf(p->capabilities, sizeof p->capabilities, "%s", capabilities ? capabilities : "");
    buffer_init(&p->buffer);
    p->context = zmq_ctx_new();
    p->socket = p->context ? zmq_socket(p->context, ZMQ_REP) : NULL;
    if (!p->socket) {
        nc_error_set(err, PROTO_ERR_TRANSPORT, "cannot create a ZeroMQ socket: %s", zmq_strerror(errno));
        proto_participant_close(p);
        return -1;
    }
    set_common_options(p->socket, &p->options, 2000); /* let the last reply go out on close */
    int idle = p->options.idle_timeout_ms > 0 ? p->options.idle_timeout_ms : -1;
    zmq_setsockopt(p->socket, ZMQ_RCVTIMEO, &idle, sizeof idle);
    if (zmq_bind(p->socket, endpoint) != 0) {
        nc_error_set(err, PROTO_ERR_TRANSPORT, "cannot bind %s: %s", endpoint, zmq_strerror(errno));
        proto_participant_close(p);
        return -1;
    }
    size_t size = sizeof p->endpoint;
    if (zmq_getsockopt(p->socket, ZMQ_LAST_ENDPOINT, p->endpoint, &size) != 0)
        snprintf(p->endpoint, sizeof p->endpoint, "%s", endpoint);
    *out = p;
    return 0;
}

const char *proto_participant_endpoint(const proto_participant *p)
{
    return p->endpoint;
}

static int participant_send(proto_participant *p, proto_message *reply, nc_error *err)
{
    reply->is_reply = 1;
    reply->version = p->version ? p->version : PROTO_VERSION_MIN;
    snprintf(reply->session, sizeof reply->session, "%s", p->version >= 2 ? p->session : "");
    p->awaiting_reply = 0;
    return send_message(p->socket, reply, "the coupler", err);
}

int proto_participant_version(const proto_participant *p) { return p->version; }

int proto_participant_reply_error(proto_participant *p, const char *reason, nc_error *err)
{
    return proto_participant_reply_failure(p, reason, 0, err);
}

int proto_participant_reply_failure(proto_participant *p, const char *reason, int retryable,
                                    nc_error *err)
{
    if (!p->awaiting_reply)
        return nc_error_set(err, PROTO_ERR_USAGE, "reply without a pending command");
    proto_message m;
    memset(&m, 0, sizeof m);
    proto_message_init(&m, PROTO_MSG_ERROR);
    m.step = p->last_command.step;
    m.iteration = p->last_command.iteration;
    m.time_s = p->last_command.time_s;
    m.dt_s = p->last_command.dt_s;
    snprintf(m.role, sizeof m.role, "%s", p->role);
    snprintf(m.name, sizeof m.name, "%s", p->name);
    snprintf(m.text, sizeof m.text, "%s", reason ? reason : "unspecified error");
    m.retryable = retryable != 0;
    return participant_send(p, &m, err);
}

/* Refuses the current command with `reason` (an error reply) and returns -1 with `code`. */
/* The refusal goes back in the command's own version and session, so the coupler that sent
 * it (another one, or one that skipped hello) reads the reason instead of a session error;
 * and it does not learn this session's token. */
static int refuse(proto_participant *p, const proto_message *cmd, int code, const char *reason,
                  nc_error *err)
{
    proto_message m;
    memset(&m, 0, sizeof m);
    proto_message_init(&m, PROTO_MSG_ERROR);
    m.is_reply = 1;
    m.version = cmd->version;
    snprintf(m.session, sizeof m.session, "%s", cmd->session);
    m.step = cmd->step;
    m.iteration = cmd->iteration;
    m.time_s = cmd->time_s;
    m.dt_s = cmd->dt_s;
    snprintf(m.role, sizeof m.role, "%s", p->role);
    snprintf(m.name, sizeof m.name, "%s", p->name);
    snprintf(m.text, sizeof m.text, "%s", reason);
    p->awaiting_reply = 0;
    nc_error send_error;
    if (send_message(p->socket, &m, "the coupler", &send_error)) {
        if (err) *err = send_error;
        return -1;
    }
    return nc_error_set(err, code, "%s", reason);
}

/* HELLO: the version is the newest both sides speak; version 2 takes the coupler's session
 * token, and a participant already serving one session refuses a second coupler. */
static int answer_hello(proto_participant *p, const proto_message *hello, nc_error *err)
{
    char reason[PROTO_TEXT_MAX];
    if (p->version >= 2 && strcmp(hello->session, p->session) != 0) {
        /* keep serving the coupler it has */
        snprintf(reason, sizeof reason, "%s: refused hello from another coupler: this "
                 "participant already serves one; one coupler per participant", p->role);
        return refuse(p, hello, PROTO_ERR_SESSION, reason, err);
    }
    int offered = hello->offered_version > 0 ? hello->offered_version : hello->version;
    int version = offered < PROTO_VERSION ? offered : PROTO_VERSION;
    if (version >= 2 && !hello->session[0]) {
        snprintf(reason, sizeof reason, "%s: refused hello: version 2 needs a session token",
                 p->role);
        return refuse(p, hello, PROTO_ERR_SESSION, reason, err);
    }
    p->version = version;
    snprintf(p->session, sizeof p->session, "%s", version >= 2 ? hello->session : "");
    proto_message *r = &p->hello_reply;
    proto_message_init(r, PROTO_MSG_HELLO);
    snprintf(r->role, sizeof r->role, "%s", p->role);
    snprintf(r->name, sizeof r->name, "%s", p->name);
    snprintf(r->text, sizeof r->text, "%s", p->capabilities);
    /* the coupler checks that its reply timeout is shorter than this (protocol/README.md §6) */
    proto_message_set_value(r, "idle_timeout_s",
                            p->options.idle_timeout_ms > 0 ? p->options.idle_timeout_ms / 1000.0 : 0.0,
                            NULL);
    return participant_send(p, r, err);
}

/* Version 2: a command must carry the agreed version and the session token of hello. */
static int check_session(proto_participant *p, const proto_message *command, nc_error *err)
{
    char reason[PROTO_TEXT_MAX];
    if (p->version == 0) {
        if (command->version < 2) return 0;   /* a version-1 coupler may skip hello */
        snprintf(reason, sizeof reason, "%s: refused %s: no hello yet (version 2 starts with "
                 "hello)", p->role, proto_type_name(command->type));
        return refuse(p, command, PROTO_ERR_SESSION, reason, err);
    }
    if (p->version >= 2 && strcmp(command->session, p->session) != 0) {
        snprintf(reason, sizeof reason, "%s: refused %s from another coupler (session '%s'; "
                 "this participant serves session %s)", p->role, proto_type_name(command->type),
                 command->session, p->session);
        return refuse(p, command, PROTO_ERR_SESSION, reason, err);
    }
    if (command->version != p->version) {
        snprintf(reason, sizeof reason, "%s: refused %s of version %d after agreeing on version "
                 "%d in hello", p->role, proto_type_name(command->type), command->version,
                 p->version);
        return refuse(p, command, PROTO_ERR_VERSION, reason, err);
    }
    return 0;
}

int proto_participant_receive(proto_participant *p, proto_message *command, nc_error *err)
{
    if (p->awaiting_reply) { /* keep REP in step: the previous command gets an error */
        char what[200];
        describe(&p->last_command, what, sizeof what);
        char reason[300];
        snprintf(reason, sizeof reason, "participant did not answer %s", what);
        if (proto_participant_reply_error(p, reason, err)) return -1;
    }
    for (;;) {
        nc_error decode_error;
        nc_error_clear(&decode_error);
        int rc = receive_message(p->socket, &p->buffer, command, p->options.max_bytes,
                                 "the coupler", &decode_error);
        if (rc == 1)
            return nc_error_set(err, PROTO_ERR_IDLE,
                                "no command from the coupler for %.1f s (idle timeout) on %s; "
                                "the coupler has probably gone away",
                                p->options.idle_timeout_ms / 1000.0, p->endpoint);
        p->awaiting_reply = 1;
        if (rc != 0) {
            if (decode_error.code == PROTO_ERR_TRANSPORT) {
                p->awaiting_reply = 0;
                if (err) *err = decode_error;
                return -1;
            }
            char reason[PROTO_TEXT_MAX];
            snprintf(reason, sizeof reason, "%s: malformed command: %s", p->role, decode_error.message);
            /* the command could not be read: its error reply answers "step -1" (§2.2) */
            memset(&p->last_command, 0, sizeof p->last_command);
            p->last_command.step = -1;
            proto_participant_reply_error(p, reason, NULL);
            if (err) *err = decode_error;
            return nc_error_prefix(err, "malformed command from the coupler (answered with an error)");
        }
        p->last_command.type = command->type;
        p->last_command.step = command->step;
        p->last_command.iteration = command->iteration;
        p->last_command.time_s = command->time_s;
        p->last_command.dt_s = command->dt_s;
        if (command->is_reply || command->type == PROTO_MSG_ERROR) {
            proto_participant_reply_error(p, "expected a command, got a reply", NULL);
            return nc_error_set(err, PROTO_ERR_DECODE, "the coupler sent a reply (%s) instead of a command",
                                proto_type_name(command->type));
        }
        if (command->type == PROTO_MSG_HELLO) {
            if (answer_hello(p, command, err)) return -1;
            continue;
        }
        return check_session(p, command, err);
    }
}

int proto_participant_reply(proto_participant *p, proto_message *reply, nc_error *err)
{
    if (!p->awaiting_reply)
        return nc_error_set(err, PROTO_ERR_USAGE, "reply without a pending command");
    if (reply->step < 0) reply->step = p->last_command.step;
    if (reply->iteration == 0) reply->iteration = p->last_command.iteration;
    if (reply->time_s == 0.0) reply->time_s = p->last_command.time_s;
    if (reply->dt_s == 0.0) reply->dt_s = p->last_command.dt_s;
    return participant_send(p, reply, err);
}

void proto_participant_close(proto_participant *p)
{
    if (!p) return;
    buffer_close(&p->buffer);
    proto_message_free(&p->hello_reply);
    if (p->socket) zmq_close(p->socket);
    if (p->context) zmq_ctx_term(p->context);
    free(p);
}

/* ---- coupler side (peer) ---------------------------------------------------------------- */

/* A session token: 16 hex digits from the system's random source (time, process and address
 * when it cannot be read); it tells this coupler's commands from another's. */
static void make_session(char *out, size_t size, const void *salt)
{
    uint64_t x = 0;
    FILE *f = fopen("/dev/urandom", "rb");
    if (!f || fread(&x, sizeof x, 1, f) != 1) {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        x = ((uint64_t)ts.tv_sec * 1000000007u) ^ (uint64_t)ts.tv_nsec ^ (uint64_t)(uintptr_t)salt;
        x ^= (uint64_t)clock() << 32;
    }
    if (f) fclose(f);
    snprintf(out, size, "%016llx", (unsigned long long)x);
}

int proto_peer_open(proto_peer **out, const char *peer_name, const char *endpoint,
                    const proto_options *options, nc_error *err)
{
    *out = NULL;
    proto_peer *peer = calloc(1, sizeof *peer);
    if (!peer) return nc_error_set(err, PROTO_ERR_TRANSPORT, "out of memory");
    if (options) peer->options = *options;
    else proto_options_default(&peer->options);
    snprintf(peer->name, sizeof peer->name, "%s", peer_name);
    snprintf(peer->endpoint, sizeof peer->endpoint, "%s", endpoint);
    snprintf(peer->last_sent, sizeof peer->last_sent, "nothing yet");
    make_session(peer->session, sizeof peer->session, peer);
    buffer_init(&peer->buffer);
    peer->context = zmq_ctx_new();
    peer->socket = peer->context ? zmq_socket(peer->context, ZMQ_REQ) : NULL;
    if (!peer->socket) {
        nc_error_set(err, PROTO_ERR_TRANSPORT, "cannot create a ZeroMQ socket: %s", zmq_strerror(errno));
        proto_peer_close(peer);
        return -1;
    }
    set_common_options(peer->socket, &peer->options, 0);
    int on = 1;
    zmq_setsockopt(peer->socket, ZMQ_REQ_RELAXED, &on, sizeof on);
    zmq_setsockopt(peer->socket, ZMQ_REQ_CORRELATE, &on, sizeof on);
    int send_timeout = peer->options.timeout_ms;
    zmq_setsockopt(peer->socket, ZMQ_SNDTIMEO, &send_timeout, sizeof send_timeout);
    int slice = peer->options.timeout_ms < PEER_WAIT_SLICE_MS ? peer->options.timeout_ms : PEER_WAIT_SLICE_MS;
    zmq_setsockopt(peer->socket, ZMQ_RCVTIMEO, &slice, sizeof slice);
    char monitor_endpoint[64];
    snprintf(monitor_endpoint, sizeof monitor_endpoint, "inproc://proto-monitor-%p", (void *)peer);
    if (zmq_socket_monitor(peer->socket, monitor_endpoint,
                           ZMQ_EVENT_CONNECTED | ZMQ_EVENT_DISCONNECTED) == 0) {
        peer->monitor = zmq_socket(peer->context, ZMQ_PAIR);
        if (peer->monitor && zmq_connect(peer->monitor, monitor_endpoint) != 0) {
            zmq_close(peer->monitor);
            peer->monitor = NULL;
        }
    }
    if (zmq_connect(peer->socket, endpoint) != 0) {
        nc_error_set(err, PROTO_ERR_TRANSPORT, "participant '%s': cannot connect to %s: %s",
                     peer_name, endpoint, zmq_strerror(errno));
        proto_peer_close(peer);
        return -1;
    }
    *out = peer;
    return 0;
}

const char *proto_peer_name(const proto_peer *peer) { return peer->name; }
int proto_peer_version(const proto_peer *peer) { return peer->version; }
const char *proto_peer_session(const proto_peer *peer) { return peer->session; }

void proto_peer_join(proto_peer *peer, const char *session, int version)
{
    snprintf(peer->session, sizeof peer->session, "%s", session);
    peer->version = version;
}

void proto_peer_set_timeout(proto_peer *peer, int timeout_ms)
{
    peer->options.timeout_ms = timeout_ms;
    zmq_setsockopt(peer->socket, ZMQ_SNDTIMEO, &timeout_ms, sizeof timeout_ms);
    int slice = timeout_ms < PEER_WAIT_SLICE_MS ? timeout_ms : PEER_WAIT_SLICE_MS;
    zmq_setsockopt(peer->socket, ZMQ_RCVTIMEO, &slice, sizeof slice);
}
const char *proto_peer_endpoint(const proto_peer *peer) { return peer->endpoint; }

/* Reads pending monitor events; returns 1 if the peer's connection was closed. */
static int peer_lost(proto_peer *peer)
{
    int lost = 0;
    for (;;) {
        zmq_msg_t event, address;
        zmq_msg_init(&event);
        if (zmq_msg_recv(&event, peer->monitor, ZMQ_DONTWAIT) < 0) {
            zmq_msg_close(&event);
            break;
        }
        uint16_t id = 0;
        if (zmq_msg_size(&event) >= 2) memcpy(&id, zmq_msg_data(&event), sizeof id);
        int more = zmq_msg_more(&event);
        zmq_msg_close(&event);
        if (more) { /* second frame: the address */
            zmq_msg_init(&address);
            zmq_msg_recv(&address, peer->monitor, 0);
            zmq_msg_close(&address);
        }
        if (id == ZMQ_EVENT_CONNECTED) peer->connected = peer->ever_connected = 1;
        if (id == ZMQ_EVENT_DISCONNECTED && peer->connected) {
            peer->connected = 0;
            lost = 1;
        }
    }
    return lost;
}

/* A reply must answer the request: marked as a reply, of its type (or an error); in version
 * 2 also of its step, iteration and session, so a stale or foreign reply is caught. */
static int check_reply(const proto_peer *peer, const char *label, const proto_message *reply,
                       nc_error *err)
{
    if (!reply->is_reply)
        return nc_error_set(err, PROTO_ERR_DECODE, "%s sent a bad reply to %s: not marked as a "
                            "reply (\"reply\": true)", label, peer->last_sent);
    int v2 = peer->version >= 2 && peer->pending_type != PROTO_MSG_HELLO;
    if (v2 && strcmp(reply->session, peer->session) != 0)
        return nc_error_set(err, PROTO_ERR_DECODE, "%s sent a bad reply to %s: session '%s' "
                            "instead of %s", label, peer->last_sent, reply->session, peer->session);
    /* an error reply of step -1, iteration 0 answers a command the participant could not read
     * (malformed): its reason matters more than the echo */
    int unread = reply->type == PROTO_MSG_ERROR && reply->step == -1 && reply->iteration == 0;
    if (v2 && !unread &&
        (reply->step != peer->pending_step || reply->iteration != peer->pending_iteration))
        return nc_error_set(err, PROTO_ERR_DECODE, "%s sent a bad reply to %s: it answers step "
                            "%ld, iteration %d (a stale reply?)", label, peer->last_sent,
                            reply->step, reply->iteration);
    if (reply->type == PROTO_MSG_ERROR)
        return nc_error_set(err, reply->retryable ? PROTO_ERR_STEP_FAILED : PROTO_ERR_PEER,
                            "%s reported an error for %s: %s", label, peer->last_sent,
                            reply->text[0] ? reply->text : "(no reason given)");
    if (reply->type != peer->pending_type)
        return nc_error_set(err, PROTO_ERR_DECODE, "%s answered %s with '%s'", label,
                            peer->last_sent, proto_type_name(reply->type));
    return 0;
}

static void peer_label(const proto_peer *peer, char *label, size_t size)
{
    snprintf(label, size, "participant '%s' at %s", peer->name, peer->endpoint);
}

int proto_peer_send(proto_peer *peer, const proto_message *request, nc_error *err)
{
    char label[PROTO_NAME_MAX + 300];
    peer_label(peer, label, sizeof label);
    describe(request, peer->last_sent, sizeof peer->last_sent);
    peer->pending = 0;
    /* a peer that went away between two requests is reported now, not after the timeout */
    if (peer->monitor && (peer_lost(peer) || (peer->ever_connected && !peer->connected)))
        return nc_error_set(err, PROTO_ERR_DISCONNECTED,
                            "%s closed the connection before %s (did the process exit?)", label,
                            peer->last_sent);
    /* the header goes out with the agreed version and this coupler's token */
    proto_message *header = malloc(sizeof *header);
    if (!header) return nc_error_set(err, PROTO_ERR_TRANSPORT, "%s: out of memory", label);
    *header = *request;
    if (request->type != PROTO_MSG_HELLO) {
        header->version = peer->version ? peer->version : PROTO_VERSION_MIN;
        snprintf(header->session, sizeof header->session, "%s",
                 header->version >= 2 ? peer->session : "");
    }
    int sent = send_message(peer->socket, header, label, err);
    free(header);
    if (sent) {
        if (err && err->code == PROTO_ERR_TIMEOUT)
            return nc_error_set(err, PROTO_ERR_TIMEOUT,
                                "%s: not reachable within %.1f s (is it running?); last message: %s",
                                label, peer->options.timeout_ms / 1000.0, peer->last_sent);
        return -1;
    }
    peer->pending = 1;
    peer->pending_type = request->type;
    peer->pending_step = request->step;
    peer->pending_iteration = request->iteration;
    return 0;
}

int proto_peer_receive(proto_peer *peer, proto_message *reply, nc_error *err)
{
    char label[PROTO_NAME_MAX + 300];
    peer_label(peer, label, sizeof label);
    if (!peer->pending)
        return nc_error_set(err, PROTO_ERR_TRANSPORT, "%s: no request awaits a reply", label);
    peer->pending = 0;
    /* wait in slices of the socket's receive timeout, looking at the monitor in between, so a
     * peer that dies is reported at once rather than after the whole timeout */
    double started_ms = now_ms();
    for (;;) {
        nc_error decode_error;
        nc_error_clear(&decode_error);
        int rc = receive_message(peer->socket, &peer->buffer, reply, peer->options.max_bytes,
                                 label, &decode_error);
        if (rc == 0) break;
        if (rc < 0) {
            if (err) *err = decode_error;
            if (decode_error.code == PROTO_ERR_TRANSPORT) return -1;
            return nc_error_prefix(err, "%s sent a bad reply to %s", label, peer->last_sent);
        }
        if (peer->monitor && peer_lost(peer))
            return nc_error_set(err, PROTO_ERR_DISCONNECTED,
                                "%s closed the connection while handling %s (did the process exit, or was the message over its size limit?)",
                                label, peer->last_sent);
        if (now_ms() - started_ms >= peer->options.timeout_ms)
            return nc_error_set(err, PROTO_ERR_TIMEOUT, "%s did not answer within %.1f s; last message: %s",
                                label, peer->options.timeout_ms / 1000.0, peer->last_sent);
    }
    return check_reply(peer, label, reply, err);
}

int proto_peer_request(proto_peer *peer, const proto_message *request, proto_message *reply,
                       nc_error *err)
{
    if (proto_peer_send(peer, request, err)) return -1;
    return proto_peer_receive(peer, reply, err);
}

int proto_peer_hello(proto_peer *peer, proto_message *reply, nc_error *err)
{
    proto_message hello;
    memset(&hello, 0, sizeof hello);
    proto_message_init(&hello, PROTO_MSG_HELLO);
    /* sent as the oldest version, so a version-1 participant reads it; `versions` offers the
     * newer ones and the reply's version is the one agreed */
    hello.version = PROTO_VERSION_MIN;
    hello.offered_version = PROTO_VERSION;
    snprintf(hello.session, sizeof hello.session, "%s", peer->session);
    snprintf(hello.role, sizeof hello.role, "coupler");
    snprintf(hello.name, sizeof hello.name, "netcouple coupler");
    peer->version = 0;
    if (proto_peer_request(peer, &hello, reply, err)) return -1;
    if (reply->version >= 2 && strcmp(reply->session, peer->session) != 0)
        return nc_error_set(err, PROTO_ERR_DECODE, "participant '%s' at %s answered hello with "
                            "session '%s' instead of %s", peer->name, peer->endpoint,
                            reply->session, peer->session);
    peer->version = reply->version;
    return 0;
}

void proto_peer_close(proto_peer *peer)
{
    if (!peer) return;
    buffer_close(&peer->buffer);
    if (peer->monitor) {
        zmq_socket_monitor(peer->socket, NULL, 0);
        zmq_close(peer->monitor);
    }
    if (peer->socket) zmq_close(peer->socket);
    if (peer->context) zmq_ctx_term(peer->context);
    free(peer);
}
