/* chk_wire — raw request/reply for netcouple-check (chk_wire.h). */
#include "chk_wire.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zmq.h>

#define WIRE_FRAMES_MAX (PROTO_MAX_ARRAYS + 1)

int chk_wire_open(chk_wire *w, const char *endpoint, double timeout_s, nc_error *err)
{
    memset(w, 0, sizeof *w);
    snprintf(w->endpoint, sizeof w->endpoint, "%s", endpoint);
    w->timeout_s = timeout_s;
    w->context = zmq_ctx_new();
    w->socket = w->context ? zmq_socket(w->context, ZMQ_REQ) : NULL;
    if (!w->socket) {
        nc_error_set(err, PROTO_ERR_TRANSPORT, "cannot create a ZeroMQ socket: %s", zmq_strerror(errno));
        chk_wire_close(w);
        return -1;
    }
    int on = 1, linger = 0, send_ms = (int)(timeout_s * 1000.0);
    zmq_setsockopt(w->socket, ZMQ_REQ_RELAXED, &on, sizeof on);
    zmq_setsockopt(w->socket, ZMQ_REQ_CORRELATE, &on, sizeof on);
    zmq_setsockopt(w->socket, ZMQ_LINGER, &linger, sizeof linger);
    zmq_setsockopt(w->socket, ZMQ_SNDTIMEO, &send_ms, sizeof send_ms);
    if (zmq_connect(w->socket, endpoint) != 0) {
        nc_error_set(err, PROTO_ERR_TRANSPORT, "cannot connect to %s: %s", endpoint, zmq_strerror(errno));
        chk_wire_close(w);
        return -1;
    }
    return 0;
}

void chk_wire_close(chk_wire *w)
{
    if (w->socket) zmq_close(w->socket);
    if (w->context) zmq_ctx_term(w->context);
    w->socket = w->context = NULL;
}

int chk_wire_send_raw(chk_wire *w, const void *const *frames, const size_t *lengths, size_t n,
                      nc_error *err)
{
    for (size_t i = 0; i < n; i++) {
        if (zmq_send(w->socket, frames[i], lengths[i], i + 1 < n ? ZMQ_SNDMORE : 0) < 0)
            return nc_error_set(err, errno == EAGAIN ? PROTO_ERR_TIMEOUT : PROTO_ERR_TRANSPORT,
                                "cannot send to %s: %s", w->endpoint, zmq_strerror(errno));
    }
    return 0;
}

int chk_wire_send(chk_wire *w, const proto_message *m, nc_error *err)
{
    char *header = NULL;
    size_t header_length = 0;
    if (proto_encode_header(m, &header, &header_length, err)) return -1;
    const void *frames[WIRE_FRAMES_MAX];
    size_t lengths[WIRE_FRAMES_MAX];
    size_t n = 0;
    for (size_t i = 0; i < m->n_arrays; i++, n++) {
        frames[n] = m->arrays[i].data;
        lengths[n] = m->arrays[i].count * proto_dtype_size(m->arrays[i].dtype);
    }
    frames[n] = header;
    lengths[n++] = header_length;
    int rc = chk_wire_send_raw(w, frames, lengths, n, err);
    free(header);
    return rc;
}

int chk_wire_receive(chk_wire *w, proto_message *reply, nc_error *err)
{
    zmq_pollitem_t item = {w->socket, 0, ZMQ_POLLIN, 0};
    int rc = zmq_poll(&item, 1, (long)(w->timeout_s * 1000.0));
    if (rc < 0)
        return nc_error_set(err, PROTO_ERR_TRANSPORT, "waiting for a reply from %s: %s",
                            w->endpoint, zmq_strerror(errno));
    if (rc == 0)
        return nc_error_set(err, PROTO_ERR_TIMEOUT, "no reply from %s within %.1f s", w->endpoint,
                            w->timeout_s);
    zmq_msg_t frames[WIRE_FRAMES_MAX];
    size_t n = 0;
    int more = 1, too_many = 0, failed = 0;
    while (more) {
        zmq_msg_t part;
        zmq_msg_init(&part);
        if (zmq_msg_recv(&part, w->socket, 0) < 0) {
            zmq_msg_close(&part);
            failed = 1;
            break;
        }
        more = zmq_msg_more(&part);
        if (n < WIRE_FRAMES_MAX) frames[n++] = part;
        else {
            too_many = 1;
            zmq_msg_close(&part);
        }
    }
    int result = 0;
    if (failed)
        result = nc_error_set(err, PROTO_ERR_TRANSPORT, "receiving from %s: %s", w->endpoint,
                              zmq_strerror(errno));
    else if (too_many || n == 0)
        result = nc_error_set(err, PROTO_ERR_DECODE, "reply has %s frames", too_many ? "too many" : "no");
    else {
        const void *data[WIRE_FRAMES_MAX];
        size_t lengths[WIRE_FRAMES_MAX];
        for (size_t i = 0; i + 1 < n; i++) {
            data[i] = zmq_msg_data(&frames[i]);
            lengths[i] = zmq_msg_size(&frames[i]);
        }
        result = proto_decode(reply, zmq_msg_data(&frames[n - 1]), zmq_msg_size(&frames[n - 1]),
                              data, lengths, n - 1, PROTO_DEFAULT_MAX_BYTES, err);
    }
    for (size_t i = 0; i < n; i++) zmq_msg_close(&frames[i]);
    return result;
}

int chk_wire_request(chk_wire *w, const proto_message *m, proto_message *reply, nc_error *err)
{
    if (chk_wire_send(w, m, err)) return -1;
    return chk_wire_receive(w, reply, err);
}
