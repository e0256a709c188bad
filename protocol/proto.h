/* proto — the netcouple coupling protocol: message model, wire codec and ZeroMQ endpoints.
 *
 * A message is a multipart ZeroMQ message: frames 1..n are the raw little-endian bytes of the
 * arrays, and the LAST frame is a UTF-8 JSON header (type, version, step, iteration, time,
 * dt, status, descriptors of the arrays in frame order, named scalar values, text fields).
 * The coupler sends a command, the participant (FEM, DEM or any third-party solver) replies.
 * The full specification is protocol/README.md; this header is the C binding.
 *
 * Memory: arrays of a message received through an endpoint point into that endpoint's
 * receive buffers (no copy) and stay valid until the next receive or request on the same
 * endpoint; copy what must live longer. proto_decode() instead copies into buffers the
 * message owns and reuses (no allocation in a steady exchange). Arrays added with
 * proto_message_add_* point to the caller's memory, which must stay valid until sent.
 * Errors follow nc_error.h: 0 on success, -1 with a message.
 */
#ifndef PROTO_H
#define PROTO_H

#include <stddef.h>
#include <stdint.h>
#include "nc_error.h"

#define PROTO_VERSION 2          /* the newest version this library speaks */
#define PROTO_VERSION_MIN 1      /* the oldest one it still serves (negotiated in hello) */
#define PROTO_MAX_ARRAYS 16
#define PROTO_MAX_VALUES 16
#define PROTO_NAME_MAX 64
#define PROTO_TEXT_MAX 512
#define PROTO_DEFAULT_MAX_BYTES (512u * 1024u * 1024u) /* whole-message limit */
#define PROTO_DEFAULT_TIMEOUT_MS 60000
#define PROTO_DEFAULT_IDLE_TIMEOUT_MS 300000

/* Error codes carried in nc_error.code by this library. */
enum {
    PROTO_ERR_DECODE = 10,   /* malformed message */
    PROTO_ERR_VERSION = 11,  /* protocol version mismatch */
    PROTO_ERR_TIMEOUT = 12,  /* peer did not answer in time */
    PROTO_ERR_PEER = 13,     /* peer replied with an error message */
    PROTO_ERR_TRANSPORT = 14,/* ZeroMQ failure */
    PROTO_ERR_IDLE = 15,     /* participant: no command within the idle time */
    PROTO_ERR_USAGE = 16,    /* wrong use of the API (missing array, bad shape, ...) */
    PROTO_ERR_DISCONNECTED = 17,/* peer closed its connection (process exited?) */
    PROTO_ERR_STEP_FAILED = 18, /* a handler's step failed but may succeed with a smaller dt
                                   (sent as a retryable error); the peer's error reply said so */
    PROTO_ERR_SESSION = 19      /* command from another coupler, or before hello (version 2) */
};

typedef enum {
    PROTO_MSG_INVALID = 0,
    PROTO_MSG_HELLO,        /* handshake: version, role, name, capabilities */
    PROTO_MSG_INTERFACE,    /* interface mesh: FEM -> coupler -> DEM */
    PROTO_MSG_BEGIN_STEP,   /* start a step (time, dt); solver saves start-of-step state */
    PROTO_MSG_SOLVE,        /* solve iteration k of the step with the given input arrays */
    PROTO_MSG_ACCEPT_STEP,  /* commit the step, write output when due */
    PROTO_MSG_SHUTDOWN,     /* finish: close files, exit */
    PROTO_MSG_CHECKPOINT,   /* version 2: save the complete state under a name, durably */
    PROTO_MSG_RESUME,       /* version 2: continue from a named checkpoint (before any step) */
    PROTO_MSG_ERROR,        /* reply only: the command failed; `text` says why */
    PROTO_MSG_COUNT
} proto_msg_type;

typedef enum { PROTO_F64 = 0, PROTO_I32 = 1 } proto_dtype;

typedef struct proto_array {
    char name[PROTO_NAME_MAX];
    proto_dtype dtype;
    int ndim;              /* 1 or 2 */
    size_t shape[2];       /* shape[1] = 1 when ndim == 1 */
    size_t count;          /* shape[0] * shape[1] */
    const void *data;      /* points to owned storage (received) or caller memory (to send) */
} proto_array;

typedef struct proto_value {
    char name[PROTO_NAME_MAX];
    double value;
} proto_value;

typedef struct proto_message {
    proto_msg_type type;
    int version;
    int is_reply;                  /* 1 in a participant's reply */
    long step;                     /* 0-based step counter, -1 when not applicable */
    int iteration;                 /* 1-based interface iteration in the step, 0 if none */
    double time_s;                 /* start time of the step [s] */
    double dt_s;                   /* step size [s] */
    char role[PROTO_NAME_MAX];     /* hello: "coupler", "fem", "dem" or any other word */
    char name[PROTO_NAME_MAX];     /* hello: program name, e.g. "netcouple fem_solver" */
    char text[PROTO_TEXT_MAX];     /* error reason, or capabilities (space separated) */
    char session[PROTO_NAME_MAX];  /* version 2: the coupler's token from hello, echoed */
    int retryable;                 /* error reply: a smaller step may succeed (version 2) */
    int offered_version;           /* hello command: newest version the coupler speaks (0: the
                                      header's version only) */
    size_t n_arrays;
    proto_array arrays[PROTO_MAX_ARRAYS];
    size_t n_values;
    proto_value values[PROTO_MAX_VALUES];
    /* owned receive buffers (reused between receives) */
    void *storage[PROTO_MAX_ARRAYS];
    size_t storage_capacity[PROTO_MAX_ARRAYS];
} proto_message;

/* ---- message building / reading ------------------------------------------------------- */

const char *proto_type_name(proto_msg_type type);   /* "hello", ... ; "invalid" */
proto_msg_type proto_type_from_name(const char *name); /* PROTO_MSG_INVALID if unknown */

/* Starts a message: zeroes the fields (keeps owned buffers), sets type and version. */
void proto_message_init(proto_message *m, proto_msg_type type);
void proto_message_free(proto_message *m);          /* frees owned buffers */

/* Adds an array pointing to caller memory: rows × cols values (cols = 0 means 1-D). */
int proto_message_add_f64(proto_message *m, const char *name, const double *data, size_t rows,
                          size_t cols, nc_error *err);
int proto_message_add_i32(proto_message *m, const char *name, const int32_t *data, size_t rows,
                          size_t cols, nc_error *err);
int proto_message_set_value(proto_message *m, const char *name, double value, nc_error *err);

/* Finds an array; with expected_rows/cols != 0 the shape must match (cols 0 = 1-D or any).
 * Fails naming the array and what was expected. */
int proto_message_get_f64(const proto_message *m, const char *name, size_t expected_rows,
                          size_t expected_cols, const double **data, size_t *rows,
                          nc_error *err);
int proto_message_get_i32(const proto_message *m, const char *name, size_t expected_rows,
                          size_t expected_cols, const int32_t **data, size_t *rows,
                          nc_error *err);
/* The array called `name`, or NULL. */
const proto_array *proto_message_find(const proto_message *m, const char *name);
/* 1 if the space-separated word list `capabilities` holds `word`. */
int proto_has_capability(const char *capabilities, const char *word);
/* Named scalar: returns fallback when absent. */
double proto_message_value(const proto_message *m, const char *name, double fallback);
int proto_message_has_value(const proto_message *m, const char *name);

/* ---- wire codec (transport independent; used by the endpoints and the fuzzer) ---------- */

size_t proto_dtype_size(proto_dtype dtype);          /* 8 for f64, 4 for i32 */

/* Encodes the header to JSON text (malloc'ed, caller frees). */
int proto_encode_header(const proto_message *m, char **json, size_t *length, nc_error *err);
/* Decodes header + frames into m, copying frame bytes into m's owned storage and checking
 * everything: JSON syntax, known type, version, field types, array count = frame count,
 * names, dtypes, shapes and byte lengths, total size <= max_bytes, NaN/Inf in f64 arrays.
 * On failure m is left with n_arrays = 0 and err says what was wrong. */
int proto_decode(proto_message *m, const void *header, size_t header_length,
                 const void *const *frames, const size_t *frame_lengths, size_t n_frames,
                 size_t max_bytes, nc_error *err);

/* The same checks, but aligned little-endian frames are used in place (arrays point into
 * `frames`, which must outlive the message's use); misaligned ones are copied. */
int proto_decode_borrowed(proto_message *m, const void *header, size_t header_length,
                          const void *const *frames, const size_t *frame_lengths,
                          size_t n_frames, size_t max_bytes, nc_error *err);

/* ---- endpoints ------------------------------------------------------------------------ */

typedef struct proto_options {
    int timeout_ms;        /* coupler: how long to wait for a reply (default 60 s) */
    int idle_timeout_ms;   /* participant: exit when no command arrives for this long
                              (default 300 s; <= 0 waits forever) */
    size_t max_bytes;      /* largest accepted message (default 512 MiB) */
} proto_options;

void proto_options_default(proto_options *options);

/* Participant side: a solver serving the coupler. It binds `endpoint`
 * ("tcp://127.0.0.1:5555", "tcp://127.0.0.1:*" for a free port, "ipc://PATH" for a Unix socket at PATH). */
typedef struct proto_participant proto_participant;

int proto_participant_open(proto_participant **p, const char *endpoint, const char *role,
                           const char *name, const char *capabilities,
                           const proto_options *options, nc_error *err);
/* The endpoint actually bound (with the port chosen for "*"). */
const char *proto_participant_endpoint(const proto_participant *p);
/* Waits for the next command. HELLO is answered inside (role, name, capabilities; version
 * mismatch gets an error reply and is reported). Returns 0 with the command in `command`,
 * or -1: idle timeout (PROTO_ERR_IDLE), malformed command (an error reply has already been
 * sent; the caller may keep receiving), transport failure. */
int proto_participant_receive(proto_participant *p, proto_message *command, nc_error *err);
/* Replies to the last command; reply->type should equal the command's type. */
int proto_participant_reply(proto_participant *p, proto_message *reply, nc_error *err);
/* Replies with an error message: the command failed for `reason`. */
int proto_participant_reply_error(proto_participant *p, const char *reason, nc_error *err);
/* The same, marked retryable (version 2): the step may succeed with a smaller dt. */
int proto_participant_reply_failure(proto_participant *p, const char *reason, int retryable,
                                    nc_error *err);
/* The version agreed in hello (0 before the first hello). */
int proto_participant_version(const proto_participant *p);
void proto_participant_close(proto_participant *p);

/* Coupler side: one peer (a participant) reached at `endpoint`. */
typedef struct proto_peer proto_peer;

int proto_peer_open(proto_peer **peer, const char *peer_name, const char *endpoint,
                    const proto_options *options, nc_error *err);
/* Handshake: sends HELLO offering versions PROTO_VERSION_MIN..PROTO_VERSION with this peer's
 * session token, agrees on the participant's version (its reply's), fills role/name/
 * capabilities. Later requests carry the agreed version and the token. */
int proto_peer_hello(proto_peer *peer, proto_message *reply, nc_error *err);
/* The version agreed in hello (0 before it). */
int proto_peer_version(const proto_peer *peer);
/* This coupler's session token (sent with every command). */
const char *proto_peer_session(const proto_peer *peer);
/* Uses `session` instead of the peer's own token (a second connection of the same coupler,
 * e.g. for SHUTDOWN), and `version` as agreed (no hello on this connection). */
void proto_peer_join(proto_peer *peer, const char *session, int version);
/* Changes the reply timeout of later requests. */
void proto_peer_set_timeout(proto_peer *peer, int timeout_ms);
/* Sends `request`, waits up to timeout_ms for the reply. An error reply from the peer
 * returns -1 with PROTO_ERR_PEER and the peer's reason (PROTO_ERR_STEP_FAILED when it is
 * marked retryable); a reply that does not answer the request (not a reply, another type;
 * version 2: another step, iteration or session) returns PROTO_ERR_DECODE; a timeout returns PROTO_ERR_TIMEOUT
 * with a message naming the peer, its endpoint and the last message sent; a peer whose
 * connection closed (before or during the request) returns PROTO_ERR_DISCONNECTED at once. */
int proto_peer_request(proto_peer *peer, const proto_message *request, proto_message *reply,
                       nc_error *err);
/* proto_peer_request in two halves, so that requests to several peers overlap: send
 * (the errors of the request before the wait), then receive its reply (the errors of the
 * wait and of the reply). One request at a time per peer; a new send drops the reply of an
 * unreceived one. */
int proto_peer_send(proto_peer *peer, const proto_message *request, nc_error *err);
int proto_peer_receive(proto_peer *peer, proto_message *reply, nc_error *err);
const char *proto_peer_name(const proto_peer *peer);
const char *proto_peer_endpoint(const proto_peer *peer);
void proto_peer_close(proto_peer *peer);

#endif
