"""netcouple_participant — a minimal participant of the netcouple coupling protocol in Python.

Written from the protocol description (protocol/proto.h, protocol/proto_codec.c,
protocol/proto_transport.c): a participant binds a ZeroMQ REP socket, the coupler connects
with REQ and sends commands; every command gets exactly one reply. A message is multipart:
the raw little-endian bytes of the arrays come first, one frame per array, and the LAST frame
is a UTF-8 JSON header

    {"type": "solve", "version": 2, "reply": true, "step": 3, "iteration": 1,
     "time": 0.003, "dt": 0.001, "status": "ok", "session": "3f2a...",
     "arrays": [{"name": "force", "dtype": "f64", "shape": [n, 3]}],
     "values": {"near_interface": 1}, "role": "fem", "name": "...", "text": "..."}

whose "arrays" list describes the array frames in order.
Types: hello, interface, begin_step, solve, accept_step, shutdown, and in version 2
checkpoint and resume (protocol/README.md §3.3); an error reply has
type "error", status "error" and the reason in "text" ("retryable": true when a smaller step
may succeed).

Versions: the coupler sends hello as version 1 with "versions": [1, 2] and a "session"
token; this module answers with the newest version both speak (min(2, newest offered)) and,
in version 2, echoes the session. Every later command of version 2 must carry that session:
a command of another session ("from another coupler"), a version-2 command before hello and
a second hello with another session are refused (an error reply; not an error of this run).
A version-1 coupler (hello without "versions", or no hello at all) is served in version 1.
Every reply echoes the command's step and iteration.

Usage: subclass nothing — pass a handler object with methods interface(cmd),
begin_step(cmd), solve(cmd), accept_step(cmd), each returning (arrays, values) where arrays
is a list of (name, numpy array) and values a dict; raise ParticipantError(reason) to reply
with an error and keep serving, ParticipantError(reason, retryable=True) when the step may
succeed with a smaller dt (the coupler then retries it). serve() returns on SHUTDOWN;
Checkpoint/resume (optional): a handler that also has checkpoint_state(cmd) -> dict and
restore_state(cmd, state) is checkpoint-capable, and only then is the capability
"checkpoint" announced (when the program lists it). On CHECKPOINT the module takes the dict
(floats, ints, strings, lists, dicts, numpy arrays), writes it to
<output_dir>/checkpoint/<role>_<name>.json with every float as a hexadecimal string (bit for
bit), flushed to disk and renamed into place, keeps the two newest such files and replies
with the file name in "text"; on RESUME (before any begin_step, at most once) it reads the
file back and hands the dict to restore_state, which also reopens the handler's result files
as they were at the checkpoint. A handler must therefore not create its result files before
the first begin_step or resume.
serve_until_shutdown() wraps it with the exit codes and clean-up of a participant program:
0 after SHUTDOWN when every command was answered normally, 1 when any command (a malformed
one included) was answered with an error other than a retryable failure or a refusal of
another coupler (protocol/README.md §6), 1 after the idle timeout, 130 on Ctrl-C.
"""
import json
import math
import os
import signal
import sys

import numpy as np
import zmq

PROTOCOL_VERSION = 2        # the newest version this module speaks
PROTOCOL_VERSION_MIN = 1    # the oldest one it still serves
TYPES = ("hello", "interface", "begin_step", "solve", "accept_step", "shutdown", "checkpoint",
         "resume", "error")
DTYPES = {"f64": "<f8", "i32": "<i4"}


class ParticipantError(Exception):
    """A command that cannot be done: replied as an error, the participant keeps serving.
    retryable=True: the step may succeed with a smaller dt (sent as "retryable": true)."""

    def __init__(self, reason, retryable=False):
        super().__init__(reason)
        self.retryable = retryable


class Refused(Exception):
    """A command of another coupler, or a version-2 command before hello: refused with an
    error reply, but not an error of this participant's run."""


class IdleTimeout(Exception):
    """No command arrived within the idle timeout."""


class Command:
    """A decoded command: header fields plus arrays (numpy, read-only copies)."""

    def __init__(self, header, arrays):
        self.header = header
        self.type = header["type"]
        self.version = header["version"]
        self.step = header.get("step", -1)
        self.iteration = header.get("iteration", 0)
        self.time = header.get("time", 0.0)
        self.dt = header.get("dt", 0.0)
        self.session = header.get("session", "")
        self.is_reply = header.get("reply", False)
        self.values = header.get("values", {})
        self.arrays = arrays

    def offered_version(self):
        """hello: the newest version the coupler offers ("versions", else "version")."""
        versions = self.header.get("versions")
        return max(versions) if versions else self.version

    def array(self, name, shape=None):
        if name not in self.arrays:
            raise ParticipantError("%s command has no array '%s'" % (self.type, name))
        a = self.arrays[name]
        if shape is not None and tuple(a.shape) != tuple(shape):
            raise ParticipantError("array '%s' has shape %s, expected %s"
                                   % (name, list(a.shape), list(shape)))
        return a


def _whole(header, key, low, default):
    v = header.get(key, default)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
            or v != int(v) or v < low:
        raise ParticipantError("header field '%s': expected a whole number >= %d" % (key, low))
    return int(v)


def _check_header(header):
    """Type-checks the header fields this module reads (as the C library does)."""
    if not isinstance(header, dict):
        raise ParticipantError("header is not a JSON object")
    if header.get("type") not in TYPES:
        raise ParticipantError("unknown message type %r" % (header.get("type"),))
    if "version" not in header:
        raise ParticipantError("header has no 'version'")
    version = header["version"] = _whole(header, "version", 0, 0)
    if not PROTOCOL_VERSION_MIN <= version <= PROTOCOL_VERSION:
        raise ParticipantError("protocol version mismatch: message has version %d, this side "
                               "speaks %d to %d" % (version, PROTOCOL_VERSION_MIN,
                                                    PROTOCOL_VERSION))
    header["step"] = _whole(header, "step", -1, -1)
    header["iteration"] = _whole(header, "iteration", 0, 0)
    for key in ("time", "dt"):
        v = header.get(key, 0.0)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ParticipantError("header field '%s': expected a finite number" % key)
        header[key] = float(v)
    for key in ("reply", "retryable"):
        if key in header and not isinstance(header[key], bool):
            raise ParticipantError("header field '%s': expected true or false" % key)
    for key in ("session", "role", "name", "text"):
        if key in header and not isinstance(header[key], str):
            raise ParticipantError("header field '%s': expected a string" % key)
    versions = header.get("versions")
    if versions is not None:
        if not isinstance(versions, list) or not all(
                isinstance(v, int) and not isinstance(v, bool) and v >= 1 for v in versions):
            raise ParticipantError("header field 'versions': expected a list of whole numbers >= 1")
    values = header.get("values", {})
    if not isinstance(values, dict) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in values.values()):
        raise ParticipantError("header field 'values': expected an object of finite numbers")
    if not isinstance(header.get("arrays", []), list):
        raise ParticipantError("header field 'arrays': expected a list")


def decode(frames):
    header = json.loads(bytes(frames[-1]).decode("utf-8"))
    _check_header(header)
    descriptors = header.get("arrays", [])
    if len(descriptors) != len(frames) - 1:
        raise ParticipantError("header describes %d arrays but the message has %d data frames"
                               % (len(descriptors), len(frames) - 1))
    arrays = {}
    for d, frame in zip(descriptors, frames[:-1]):
        if not isinstance(d, dict) or not isinstance(d.get("name"), str) or not d["name"]:
            raise ParticipantError("array descriptor %r: expected an object with a name" % (d,))
        name = d["name"]
        if name in arrays:
            raise ParticipantError("array '%s' appears twice" % name)
        if d.get("dtype") not in DTYPES:
            raise ParticipantError("array '%s': dtype must be \"f64\" or \"i32\"" % name)
        shape = d.get("shape")
        if not isinstance(shape, list) or not 1 <= len(shape) <= 2 or not all(
                isinstance(x, int) and not isinstance(x, bool) and x >= 0 for x in shape):
            raise ParticipantError("array '%s': shape must be [rows] or [rows, columns]" % name)
        a = np.frombuffer(bytes(frame), dtype=DTYPES[d["dtype"]])
        if a.size != int(np.prod(shape)):
            raise ParticipantError("array '%s': shape %s needs %d bytes, its frame has %d"
                                   % (name, shape, int(np.prod(shape)) * a.itemsize, len(frame)))
        if d["dtype"] == "f64" and not np.isfinite(a).all():
            raise ParticipantError("array '%s': value %d is not finite"
                                   % (name, int(np.argmin(np.isfinite(a)))))
        arrays[name] = a.reshape(shape)
    return Command(header, arrays)


def _counters(frames):
    """Step, iteration and session of a message that failed to decode, when its header can
    still be read: the error reply then answers that command (a version-2 coupler checks)."""
    try:
        h = json.loads(bytes(frames[-1]).decode("utf-8"))
        step, iteration = h.get("step", -1), h.get("iteration", 0)
        session = h.get("session", "")
        if isinstance(step, int) and isinstance(iteration, int) and isinstance(session, str):
            return step, iteration, session
    except (ValueError, AttributeError, IndexError):
        pass
    return -1, 0, ""


def encode(msg_type, command, role, name, arrays=(), values=None, text="", error=False,
           version=1, session="", retryable=False, step=None, iteration=None):
    header = {
        "type": "error" if error else msg_type,
        "version": version,
        "reply": True,
        "step": step if step is not None else (command.step if command else -1),
        "iteration": iteration if iteration is not None else (command.iteration if command else 0),
        "time": command.time if command else 0.0,
        "dt": command.dt if command else 0.0,
        "status": "error" if error else "ok",
        "role": role,
        "name": name,
        "arrays": [],
        "values": {k: float(v) for k, v in (values or {}).items()},
    }
    if session:
        header["session"] = session
    if error and retryable:
        header["retryable"] = True
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


def _to_json(x):
    """A checkpoint value as JSON: floats as hexadecimal strings (exact), arrays tagged."""
    if isinstance(x, np.ndarray):
        return {"array": [_to_json(v) for v in x.ravel().tolist()], "dtype": x.dtype.str,
                "shape": list(x.shape)}
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return {"float": float(x).hex()}
    if isinstance(x, str) or x is None:
        return x
    if isinstance(x, (list, tuple)):
        return [_to_json(v) for v in x]
    if isinstance(x, dict):
        return {str(k): _to_json(v) for k, v in x.items()}
    raise ParticipantError("checkpoint: cannot save a value of type %s" % type(x).__name__)


def _from_json(x):
    if isinstance(x, dict):
        if set(x) == {"float"}:
            return float.fromhex(x["float"])
        if set(x) == {"array", "dtype", "shape"}:
            return np.array([_from_json(v) for v in x["array"]],
                            dtype=np.dtype(x["dtype"])).reshape(x["shape"])
        return {k: _from_json(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_from_json(v) for v in x]
    return x


def _valid_checkpoint_name(name):
    return isinstance(name, str) and 0 < len(name) < 64 and \
        all(c.isascii() and (c.isalnum() or c in "_-") for c in name)


class Participant:
    def __init__(self, endpoint, role, name, capabilities="restore", idle_timeout_s=300.0,
                 endpoint_file=None, output_dir="."):
        self.role = role
        self.output_dir = output_dir
        self.checkpoint_files = []   # written by this process, oldest first (two kept)
        self.name = name
        self.capabilities = capabilities
        self.idle_timeout_s = idle_timeout_s if idle_timeout_s > 0 else 0.0
        self.idle_timeout_ms = int(idle_timeout_s * 1000) if idle_timeout_s > 0 else None
        self.version = 0        # agreed in hello; 0 before it
        self.session = ""       # the coupler's token (version 2)
        self.errors = 0         # error replies that are errors of this run
        self.retryable = 0      # retryable failures (the coupler retries the step)
        self.refused = 0        # commands of another coupler / version 2 before hello
        self.last_error = ""
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

    def _reply(self, msg_type, cmd, arrays=(), values=None, text=""):
        self._send(encode(msg_type, cmd, self.role, self.name, arrays, values, text,
                          version=self.version or PROTOCOL_VERSION_MIN,
                          session=self.session if self.version >= 2 else ""))

    def _error(self, cmd, reason, retryable=False, counts=True, frames=None, echo=False):
        """An error reply answering cmd (or, for a command that did not decode, the step,
        iteration and session its header names). echo: a refusal, sent in the command's own
        version and session (protocol/README.md §2.2)."""
        step = iteration = None
        session = self.session if self.version >= 2 else ""
        version = self.version or PROTOCOL_VERSION_MIN
        if echo and cmd is not None:
            session, version = cmd.session, cmd.version
        if cmd is None and frames is not None:
            step, iteration, _ = _counters(frames)
        if retryable:
            self.retryable += 1
        elif counts:
            self.errors += 1
            self.last_error = reason
        self._send(encode("error", cmd, self.role, self.name, text=reason, error=True,
                          version=version, session=session,
                          retryable=retryable, step=step, iteration=iteration))

    @staticmethod
    def can_checkpoint(handler):
        return callable(getattr(handler, "checkpoint_state", None)) and \
            callable(getattr(handler, "restore_state", None))

    def _announced(self, handler):
        """The capability words, without "checkpoint" when the handler cannot."""
        words = self.capabilities.split()
        if not self.can_checkpoint(handler):
            words = [w for w in words if w != "checkpoint"]
        return " ".join(words)

    def _checkpoint_path(self, name):
        return os.path.join(self.output_dir, "checkpoint", "%s_%s.json" % (self.role, name))

    def _checkpoint(self, handler, cmd):
        """Saves the handler's state durably; returns the file name (the reply's text)."""
        name = cmd.header.get("text", "")
        if not _valid_checkpoint_name(name):
            raise ParticipantError("checkpoint name %r: expected letters, digits, '_', '-'"
                                   % (name,))
        state = {"step": cmd.step, "time": cmd.time, "state": handler.checkpoint_state(cmd)}
        path = self._checkpoint_path(name)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        tmp = path + ".tmp"
        try:
            with open(tmp, "w") as f:
                json.dump(_to_json(state), f)
                f.write("\n")
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, path)
            fd = os.open(os.path.dirname(path), os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        except OSError as e:
            raise ParticipantError("%s: cannot write the checkpoint: %s" % (path, e))
        if path in self.checkpoint_files:
            self.checkpoint_files.remove(path)
        self.checkpoint_files.append(path)
        while len(self.checkpoint_files) > 2:
            old = self.checkpoint_files.pop(0)
            try:
                os.remove(old)
            except OSError:
                pass
        return os.path.basename(path)

    def _resume(self, handler, cmd):
        name = cmd.header.get("text", "")
        if not _valid_checkpoint_name(name):
            raise ParticipantError("resume: checkpoint name %r: expected letters, digits, '_', "
                                   "'-'" % (name,))
        path = self._checkpoint_path(name)
        try:
            with open(path) as f:
                saved = _from_json(json.load(f))
        except (OSError, ValueError) as e:
            raise ParticipantError("%s: cannot read the checkpoint: %s" % (path, e))
        if not isinstance(saved, dict) or saved.get("step") != cmd.step or \
                saved.get("time") != cmd.time:
            raise ParticipantError("%s: checkpoint of step %r, t = %r; resume asks for step %d, "
                                   "t = %r" % (path, saved.get("step") if isinstance(saved, dict)
                                               else None, saved.get("time") if
                                               isinstance(saved, dict) else None, cmd.step,
                                               cmd.time))
        handler.restore_state(cmd, saved["state"])
        self.checkpoint_files = [path]
        return os.path.basename(path)

    def _hello(self, cmd, handler=None):
        """Agrees on the newest common version; version 2 takes the coupler's session, and a
        participant serving one session refuses a second coupler."""
        if self.version >= 2 and cmd.session != self.session:
            self.refused += 1
            self._error(cmd, "%s: refused hello from another coupler (session '%s'): this "
                        "participant already serves session %s; one coupler per participant"
                        % (self.role, cmd.session, self.session), counts=False, echo=True)
            return
        version = min(PROTOCOL_VERSION, cmd.offered_version())
        if version < PROTOCOL_VERSION_MIN:
            self._error(cmd, "%s: refused hello: no common version (offered up to %d, this "
                        "side speaks %d to %d)" % (self.role, version, PROTOCOL_VERSION_MIN,
                                                   PROTOCOL_VERSION))
            return
        if version >= 2 and not cmd.session:
            self._error(cmd, "%s: refused hello: version 2 needs a session token" % self.role,
                        echo=True)
            return
        self.version = version
        self.session = cmd.session if version >= 2 else ""
        self._reply("hello", cmd, values={"idle_timeout_s": self.idle_timeout_s},
                    text=self._announced(handler))

    def _check_session(self, cmd):
        """Raises Refused for a command this participant must not serve."""
        if self.version == 0:
            if cmd.version >= 2:
                raise Refused("%s: refused %s: no hello yet (version 2 starts with hello)"
                              % (self.role, cmd.type))
            return
        if self.version >= 2 and cmd.session != self.session:
            raise Refused("%s: refused %s from another coupler (session '%s'; this participant "
                          "serves session %s)" % (self.role, cmd.type, cmd.session, self.session))
        if cmd.version != self.version:
            raise ParticipantError("%s: refused %s of version %d after agreeing on version %d "
                                   "in hello" % (self.role, cmd.type, cmd.version, self.version))

    def serve(self, handler):
        """Answers commands until SHUTDOWN (returns) or the idle timeout (raises IdleTimeout)."""
        poller = zmq.Poller()
        poller.register(self.socket, zmq.POLLIN)
        step_open = last_solve_ok = False
        stepped = resumed = False   # a begin_step / a resume was served
        while True:
            if not poller.poll(self.idle_timeout_ms):
                raise IdleTimeout("no command from the coupler for %.1f s"
                                  % (self.idle_timeout_ms / 1000.0))
            frames = self.socket.recv_multipart()
            try:
                cmd = decode(frames)
            except (ParticipantError, ValueError, KeyError, TypeError) as e:
                self._error(None, "%s: malformed command: %s" % (self.role, e), frames=frames)
                continue
            if cmd.is_reply or cmd.type == "error":
                self._error(cmd, "%s: expected a command, got a reply (%s)" % (self.role, cmd.type))
                continue
            if cmd.type == "hello":
                self._hello(cmd, handler)
                continue
            try:
                self._check_session(cmd)
            except Refused as e:
                self.refused += 1
                self._error(cmd, str(e), counts=False, echo=True)
                continue
            except ParticipantError as e:
                self._error(cmd, str(e))
                continue
            if cmd.type == "shutdown":
                self._reply("shutdown", cmd)
                return
            # the step order of protocol/README.md §3.2: solve and accept_step belong to a
            # begun step, and accept_step needs a successful solve to commit
            if cmd.type == "solve" and not step_open or \
                    cmd.type == "accept_step" and not (step_open and last_solve_ok):
                self._error(cmd, "%s (step %d, iteration %d): refused: %s"
                            % (cmd.type, cmd.step, cmd.iteration,
                               "no step begun (begin_step must come first)" if not step_open
                               else "the step has no successful solve to accept"))
                continue
            if cmd.type in ("checkpoint", "resume"):
                # protocol/README.md §3.3: between steps only; resume once, before stepping
                why = None
                if self.version < 2 or not self.can_checkpoint(handler):
                    why = "this participant cannot (capability 'checkpoint' not announced)"
                elif cmd.type == "checkpoint" and step_open:
                    why = "inside a begun step (a checkpoint is taken after accept_step)"
                elif cmd.type == "resume" and (stepped or resumed):
                    why = "after %s (a run resumes once, before it steps)" % (
                        "begin_step" if stepped else "a resume")
                if why:
                    self._error(cmd, "%s (step %d): refused: %s" % (cmd.type, cmd.step, why))
                    continue
                try:
                    text = (self._checkpoint if cmd.type == "checkpoint" else self._resume)(
                        handler, cmd)
                except ParticipantError as e:
                    self._error(cmd, "%s (step %d): %s" % (cmd.type, cmd.step, e))
                    continue
                resumed = resumed or cmd.type == "resume"
                self._reply(cmd.type, cmd, text=text)
                continue
            method = getattr(handler, cmd.type, None)
            if method is None:
                self._error(cmd, "%s cannot do '%s'" % (self.role, cmd.type))
                continue
            if cmd.type == "solve":
                last_solve_ok = False
            try:
                arrays, values = method(cmd)
                self._reply(cmd.type, cmd, arrays, values)
            except ParticipantError as e:
                self._error(cmd, "%s (step %d, iteration %d): %s"
                            % (cmd.type, cmd.step, cmd.iteration, e), retryable=e.retryable)
                continue
            if cmd.type == "begin_step":
                step_open, last_solve_ok, stepped = True, False, True
            elif cmd.type == "solve":
                last_solve_ok = True
            elif cmd.type == "accept_step":
                step_open = last_solve_ok = False

    def close(self):
        self.socket.close()
        self.context.term()


def log(*args):
    print(*args, file=sys.stderr, flush=True)


def serve_until_shutdown(participant, handler, name, close_handler):
    """Serves handler until SHUTDOWN and returns the process exit code: 0; 1 when any command
    was answered with an error of this run (a failed handler, a malformed or out-of-place
    command; not a retryable failure, not a refused command of another coupler) or after an
    idle timeout (logged under name); 130 on SIGINT or SIGTERM (protocol/README.md §7: the
    launcher sends SIGTERM to every program when one fails). close_handler() and
    participant.close() run in every case, so results written so far stay readable."""
    code = 0

    def stop(signum, frame):
        raise KeyboardInterrupt

    try:   # only the main thread may set a handler; elsewhere SIGTERM keeps its default
        previous = signal.signal(signal.SIGTERM, stop)
    except ValueError:
        previous = None
    try:
        participant.serve(handler)
        if participant.errors:
            log("%s: %d command(s) answered with an error; the last: %s"
                % (name, participant.errors, participant.last_error))
            code = 1
    except IdleTimeout as e:
        log(name + ":", e)
        code = 1
    except KeyboardInterrupt:
        code = 130
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
        close_handler()
        participant.close()
    return code
