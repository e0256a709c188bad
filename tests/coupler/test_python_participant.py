#!/usr/bin/python3
"""The Python participant module (scripts/participants/netcouple_participant.py) on the wire:
spring_plate.py is driven by a raw ZeroMQ REQ socket as a coupler would drive it. Checked:
hello negotiates min(2, newest offered) and echoes the session, a version-1 coupler is served
in version 1, replies echo step and iteration, a command of another session, a version-2
command before hello and a second hello are refused (exit status still 0), a retryable
failure carries "retryable": true (exit 0), and malformed commands get an error reply and
make the participant exit 1 after SHUTDOWN (protocol/README.md §6); SIGTERM inside a run:
exit 130 with the results written so far readable (§7)."""
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np
import zmq

ROOT = os.environ.get("NC_ROOT", os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))))
PLATE = os.path.join(ROOT, "scripts", "participants", "spring_plate.py")
TMP = os.environ.get("NC_TMP") or tempfile.mkdtemp()
NODES = 4   # nodes_per_side 2
SESSION = "a1b2c3d4e5f60718"


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


class Plate:
    """spring_plate.py in a subprocess and a REQ socket connected to it."""

    def __init__(self, name, *extra):
        self.dir = os.path.join(TMP, name)
        os.makedirs(self.dir, exist_ok=True)
        cfg = os.path.join(self.dir, "plate.json")
        with open(cfg, "w") as f:
            json.dump({"size": 0.5, "nodes_per_side": 2, "mass": 1.0, "stiffness": 1000.0}, f)
        ep_file = os.path.join(self.dir, "fem.endpoint")
        self.proc = subprocess.Popen(
            ["/usr/bin/python3", PLATE, cfg, "--endpoint", "tcp://127.0.0.1:*", "--output",
             self.dir, "--endpoint-file", ep_file, "--idle-timeout", "30"] + list(extra),
            stderr=subprocess.PIPE, text=True)
        for _ in range(400):
            if os.path.exists(ep_file):
                break
            if self.proc.poll() is not None:
                fail("%s: spring_plate.py exited early: %s" % (name, self.proc.stderr.read()))
            time.sleep(0.025)
        with open(ep_file) as f:
            endpoint = f.read().strip()
        self.ctx = zmq.Context()
        self.sock = self.ctx.socket(zmq.REQ)
        self.sock.setsockopt(zmq.RCVTIMEO, 10000)
        self.sock.setsockopt(zmq.LINGER, 0)
        self.sock.connect(endpoint)

    def raw(self, header_text, frames=()):
        self.sock.send_multipart(list(frames) + [header_text.encode()])
        reply = self.sock.recv_multipart()
        h = json.loads(reply[-1].decode())
        if h.get("reply") is not True:
            fail("reply not marked as a reply: %s" % h)
        return h, reply[:-1]

    def send(self, header, arrays=()):
        header = dict(header)
        header["arrays"] = [{"name": n, "dtype": "f64", "shape": list(a.shape)} for n, a in arrays]
        return self.raw(json.dumps(header), [np.ascontiguousarray(a, "<f8").tobytes()
                                             for _, a in arrays])

    def finish(self):
        """Closes the socket; returns (exit status, stderr)."""
        self.sock.close()
        self.ctx.term()
        try:
            code = self.proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            fail("spring_plate.py did not exit after shutdown")
        return code, self.proc.stderr.read()


def expect(cond, what):
    if not cond:
        fail(what)


def v2(msg_type, **fields):
    h = {"type": msg_type, "version": 2, "session": SESSION}
    h.update(fields)
    return h


# 1. version 2: negotiation, echo, refusals of another coupler; exit 0
p = Plate("v2")
h, _ = p.send(v2("begin_step", step=0, dt=1e-3))
expect(h["type"] == "error" and "no hello yet" in h["text"], "v2 before hello: %s" % h)
h, _ = p.send({"type": "hello", "version": 1, "versions": [1, 2, 3], "session": SESSION,
               "role": "coupler"})
expect(h["type"] == "hello" and h["version"] == 2, "hello: %s" % h)
expect(h.get("session") == SESSION, "session not echoed: %s" % h)
expect("restore" in h.get("text", "").split(), "capabilities: %s" % h)
expect(abs(h["values"].get("idle_timeout_s", 0) - 30.0) < 1e-12, "idle_timeout_s: %s" % h)
h, _ = p.send(v2("interface", step=-1))
expect(h["type"] == "interface" and h["session"] == SESSION, "interface: %s" % h)
h, _ = p.send(v2("begin_step", step=0, dt=1e-3))
expect(h["type"] == "begin_step" and h["step"] == 0, "begin_step: %s" % h)
force = np.zeros((NODES, 3))
force[:, 2] = -2.5   # 10 N down on the 1000 N/m plate
h, frames = p.send(v2("solve", step=0, iteration=2, dt=1e-3), [("force", force)])
expect(h["type"] == "solve" and h["step"] == 0 and h["iteration"] == 2, "solve echo: %s" % h)
expect(h["version"] == 2 and h["session"] == SESSION, "solve reply: %s" % h)
u = np.frombuffer(frames[0], "<f8").reshape(NODES, 3)
expect(u[0, 2] < 0, "plate did not move down: %s" % u)
# another coupler: a command of its session, and its hello
h, _ = p.send({"type": "solve", "version": 2, "session": "ffffffffffffffff", "step": 0,
               "iteration": 3, "dt": 1e-3}, [("force", force)])
expect(h["type"] == "error" and "another coupler" in h["text"], "foreign solve: %s" % h)
h, _ = p.send({"type": "hello", "version": 1, "versions": [1, 2], "session": "ffffffffffffffff"})
expect(h["type"] == "error" and "one coupler per participant" in h["text"], "2nd hello: %s" % h)
# the first coupler goes on
h, _ = p.send(v2("accept_step", step=0, dt=1e-3))
expect(h["type"] == "accept_step", "accept after refusals: %s" % h)
h, _ = p.send(v2("shutdown"))
expect(h["type"] == "shutdown", "shutdown: %s" % h)
code, err = p.finish()
expect(code == 0, "exit %d after refusals only (expected 0): %s" % (code, err))

# 2. a version-1 coupler (no hello at all, then a hello without "versions")
p = Plate("v1")
h, _ = p.send({"type": "begin_step", "version": 1, "step": 0, "dt": 1e-3})
expect(h["type"] == "begin_step" and h["version"] == 1, "v1 without hello: %s" % h)
h, _ = p.send({"type": "hello", "version": 1, "role": "coupler"})
expect(h["type"] == "hello" and h["version"] == 1 and "session" not in h, "v1 hello: %s" % h)
h, _ = p.send({"type": "solve", "version": 1, "step": 0, "iteration": 1, "dt": 1e-3},
              [("force", force)])
expect(h["type"] == "solve" and h["version"] == 1, "v1 solve: %s" % h)
h, _ = p.send({"type": "shutdown", "version": 1})
code, err = p.finish()
expect(code == 0, "v1 run exit %d: %s" % (code, err))

# 3. retryable failure: flagged, step and iteration echoed, not an error of the run
p = Plate("retry", "--retryable-above", "1e-3")
p.send({"type": "hello", "version": 1, "versions": [1, 2], "session": SESSION})
p.send(v2("begin_step", step=7, dt=2e-3))
h, _ = p.send(v2("solve", step=7, iteration=1, dt=2e-3), [("force", force)])
expect(h["type"] == "error" and h.get("retryable") is True, "retryable: %s" % h)
expect(h["step"] == 7 and h["iteration"] == 1 and h["session"] == SESSION, "echo: %s" % h)
p.send(v2("begin_step", step=7, dt=1e-3))
h, _ = p.send(v2("solve", step=7, iteration=1, dt=1e-3), [("force", force)])
expect(h["type"] == "solve", "retry with a smaller dt: %s" % h)
p.send(v2("accept_step", step=7, dt=1e-3))
p.send(v2("shutdown"))
code, err = p.finish()
expect(code == 0, "exit %d after a retryable failure (expected 0): %s" % (code, err))

# 4. malformed commands: error replies naming the problem, then exit 1 after SHUTDOWN
p = Plate("malformed")
p.send({"type": "hello", "version": 1, "versions": [1, 2], "session": SESSION})
h, _ = p.raw("not json at all")
expect(h["type"] == "error" and "malformed command" in h["text"], "not json: %s" % h)
bad = np.array([[0.0, float("nan"), 0.0]] * NODES)
h, _ = p.send(v2("solve", step=3, iteration=2, dt=1e-3), [("force", bad)])
expect(h["type"] == "error" and "not finite" in h["text"], "NaN: %s" % h)
expect(h["step"] == 3 and h["iteration"] == 2, "malformed reply does not echo: %s" % h)
h, _ = p.send({"type": "solve", "version": 3, "session": SESSION})
expect(h["type"] == "error" and "version mismatch" in h["text"], "version 3: %s" % h)
h, _ = p.send(v2("solve", step="3"))
expect(h["type"] == "error" and "'step'" in h["text"], "step type: %s" % h)
h, _ = p.send(v2("shutdown"))
expect(h["type"] == "shutdown", "shutdown after malformed input: %s" % h)
code, err = p.finish()
expect(code == 1, "exit %d after malformed commands (expected 1)" % code)
expect("answered with an error" in err, "no message on exit: %r" % err)

# 5. SIGTERM inside a run (what the launcher sends every program when one fails): exit 130,
# the result file closed and readable with the rows of the accepted step
p = Plate("sigterm")
p.send({"type": "hello", "version": 1, "versions": [1, 2], "session": SESSION})
p.send(v2("interface", step=-1))
p.send(v2("begin_step", step=0, dt=1e-3))
p.send(v2("solve", step=0, iteration=1, dt=1e-3), [("force", force)])
p.send(v2("accept_step", step=0, dt=1e-3))
p.proc.send_signal(signal.SIGTERM)
code, err = p.finish()
expect(code == 130, "exit %d after SIGTERM (expected 130): %s" % (code, err))
written = [n for n in os.listdir(p.dir) if not n.endswith((".json", ".endpoint"))]
expect(written, "no result file in %s" % p.dir)
for n in written:
    with open(os.path.join(p.dir, n)) as f:
        rows = [l for l in f if l.strip() and not l.startswith("#")]
    print("%s after SIGTERM: %d lines" % (n, len(rows)))
    expect(len(rows) >= 2, "%s: the accepted step's row is missing" % n)
print("PASS")
