"""netcouple_participant — a minimal participant of the netcouple coupling protocol in Python.

Written from the protocol description (protocol/proto.h, protocol/proto_codec.c,
protocol/proto_transport.c): a participant binds a ZeroMQ REP socket, the coupler connects
with REQ and sends commands; every command gets exactly one reply. A message is multipart:
the raw little-endian bytes of the arrays come first, one frame per array, and the LAST frame
is a UTF-8 JSON header

    {"type": "solve", "version": 1, "reply": true, "step": 3, "iteration": 1,
     "time": 0.003, "dt": 0.001, "status": "ok",
     "arrays": [{"name": "force", "dtype": "f64", "shape": [n, 3]}],
     "values": {"near_interface": 1}, "role": "fem", "name": "...", "text": "..."}

whose "arrays" list describes the array frames in order.
Types: hello, interface, begin_step, solve, accept_step, shutdown; an error reply has
type "error", status "error" and the reason in "text".

Usage: subclass nothing — pass a handler object with methods interface(cmd),
begin_step(cmd), solve(cmd), accept_step(cmd), each returning (arrays, values) where arrays
is a list of (name, numpy array) and values a dict; raise ParticipantError(reason) to reply
with an error and keep serving. serve() returns on SHUTDOWN; serve_until_shutdown() wraps it
with the exit codes and clean-up of a participant program.
"""
import json
import os
import sys

import numpy as np
import zmq

PROTOCOL_VERSION = 1


class ParticipantError(Exception):
    """A command that cannot be done: replied as an error, the participant keeps serving."""


class IdleTimeout(Exception):
    """No command arrived within the idle timeout."""


class Command:
    """A decoded command: header fields plus arrays (numpy, read-only copies)."""

    def __init__(self, header, arrays):
        self.header = header
        self.type = header["type"]
        self.step = header.get("step", -1)
        self.iteration = header.get("iteration", 0)
        self.time = header.get("time", 0.0)
        self.dt = header.get("dt", 0.0)
        self.values = header.get("values", {})
        self.arrays = arrays

    def array(self, name, shape=None):
        if name not in self.arrays:
            raise ParticipantError("%s command has no array '%s'" % (self.type, name))
        a = self.arrays[name]
        if shape is not None and tuple(a.shape) != tuple(shape):
            raise ParticipantError("array '%s' has shape %s, expected %s"
                                   % (name, list(a.shape), list(shape)))
        return a


def decode(frames):
    header = json.loads(bytes(frames[-1]).decode("utf-8"))
    if header.get("version") != PROTOCOL_VERSION:
        raise ParticipantError("protocol version mismatch: got %r, this side speaks %d"
                               % (header.get("version"), PROTOCOL_VERSION))
    descriptors = header.get("arrays", [])
    if len(descriptors) != len(frames) - 1:
        raise ParticipantError("header describes %d arrays but the message has %d data frames"
                               % (len(descriptors), len(frames) - 1))
    arrays = {}
    for d, frame in zip(descriptors, frames[:-1]):
        dtype = {"f64": "<f8", "i32": "<i4"}[d["dtype"]]
        a = np.frombuffer(bytes(frame), dtype=dtype)
        arrays[d["name"]] = a.reshape(d["shape"])
    return Command(header, arrays)


def encode(msg_type, command, role, name, arrays=(), values=None, text="", error=False):
    header = {
        "type": "error" if error else msg_type,
        "version": PROTOCOL_VERSION,
        "reply": True,
        "step": command.step if command else -1,
        "iteration": command.iteration if command else 0,
        "time": command.time if command else 0.0,
        "dt": command.dt if command else 0.0,
        "status": "error" if error else "ok",
        "role": role,
        "name": name,
        "arrays": [],
        "values": {k: float(v) for k, v in (values or {}).items()},
    }
    if text:
        header["text"] = text[:511]
    frames = []
    for array_name, a in arrays:
        if a.dtype.kind == "f":
            a = np.ascontiguousarray(a, dtype="<f8")
            dtype = "f64"
        else:
            a = np.ascontiguousarray(a, dtype="<i4")
            dtype = "i32"
        header["arrays"].append({"name": array_name, "dtype": dtype, "shape": list(a.shape)})
        frames.append(a.tobytes())
    frames.append(json.dumps(header).encode("utf-8"))   # header last
    return frames


class Participant:
    def __init__(self, endpoint, role, name, capabilities="restore", idle_timeout_s=300.0,
                 endpoint_file=None):
        self.role = role
        self.name = name
        self.capabilities = capabilities
        self.idle_timeout_ms = int(idle_timeout_s * 1000) if idle_timeout_s > 0 else None
        self.context = zmq.Context()
        self.socket = self.context.socket(zmq.REP)
        self.socket.setsockopt(zmq.LINGER, 1000)
        self.socket.bind(endpoint)
        self.endpoint = self.socket.getsockopt_string(zmq.LAST_ENDPOINT)
        if endpoint_file:
            tmp = endpoint_file + ".tmp"
            with open(tmp, "w") as f:
                f.write(self.endpoint + "\n")
            os.replace(tmp, endpoint_file)

    def _send(self, frames):
        self.socket.send_multipart(frames)

    def serve(self, handler):
        """Answers commands until SHUTDOWN (returns) or the idle timeout (raises IdleTimeout)."""
        poller = zmq.Poller()
        poller.register(self.socket, zmq.POLLIN)
        while True:
            if not poller.poll(self.idle_timeout_ms):
                raise IdleTimeout("no command from the coupler for %.1f s"
                                  % (self.idle_timeout_ms / 1000.0))
            frames = self.socket.recv_multipart()
            try:
                cmd = decode(frames)
            except (ParticipantError, ValueError, KeyError, TypeError) as e:
                self._send(encode("error", None, self.role, self.name,
                                  text="%s: malformed command: %s" % (self.role, e), error=True))
                continue
            if cmd.type == "hello":
                self._send(encode("hello", cmd, self.role, self.name, text=self.capabilities))
                continue
            if cmd.type == "shutdown":
                self._send(encode("shutdown", cmd, self.role, self.name))
                return
            method = getattr(handler, cmd.type, None)
            if method is None:
                self._send(encode("error", cmd, self.role, self.name,
                                  text="%s cannot do '%s'" % (self.role, cmd.type), error=True))
                continue
            try:
                arrays, values = method(cmd)
                self._send(encode(cmd.type, cmd, self.role, self.name, arrays, values))
            except ParticipantError as e:
                self._send(encode("error", cmd, self.role, self.name, text=str(e), error=True))

    def close(self):
        self.socket.close()
        self.context.term()


def log(*args):
    print(*args, file=sys.stderr, flush=True)


def serve_until_shutdown(participant, handler, name, close_handler):
    """Serves handler until SHUTDOWN and returns the process exit code: 0, 1 after an idle
    timeout (logged under name), 130 on Ctrl-C. close_handler() and participant.close() run
    in every case, so results written so far stay readable."""
    code = 0
    try:
        participant.serve(handler)
    except IdleTimeout as e:
        log(name + ":", e)
        code = 1
    except KeyboardInterrupt:
        code = 130
    finally:
        close_handler()
        participant.close()
    return code
