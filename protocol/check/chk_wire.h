/* chk_wire — the coupler's end of a connection as netcouple-check needs it: a ZeroMQ REQ
 * socket that can send well-formed messages (header encoded by proto_encode_header) and, on
 * purpose, malformed ones (raw frames), and receives one reply with a bounded wait.
 *
 * Unlike proto_peer it checks nothing about the reply beyond decoding it (proto_decode):
 * the checks judge the reply themselves. The socket is relaxed and correlated, so after a
 * timeout the next request can still be sent.
 */
#ifndef CHK_WIRE_H
#define CHK_WIRE_H

#include <stddef.h>
#include "proto.h"

typedef struct chk_wire {
    void *context;
    void *socket;
    char endpoint[256];
    double timeout_s;
} chk_wire;

int chk_wire_open(chk_wire *w, const char *endpoint, double timeout_s, nc_error *err);
void chk_wire_close(chk_wire *w);

/* Sends `frames` (the last one is the header) as one multipart message. */
int chk_wire_send_raw(chk_wire *w, const void *const *frames, const size_t *lengths, size_t n,
                      nc_error *err);
/* Sends m: its array frames as they are in memory (little-endian host), then its header. */
int chk_wire_send(chk_wire *w, const proto_message *m, nc_error *err);
/* Waits up to the timeout for the reply and decodes it into `reply` (which owns its arrays).
 * 0: decoded; -1 with PROTO_ERR_TIMEOUT (nothing came), PROTO_ERR_DECODE (it came but is
 * malformed; err says why) or PROTO_ERR_TRANSPORT. */
int chk_wire_receive(chk_wire *w, proto_message *reply, nc_error *err);
/* chk_wire_send + chk_wire_receive. */
int chk_wire_request(chk_wire *w, const proto_message *m, proto_message *reply, nc_error *err);

#endif
