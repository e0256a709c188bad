#!/usr/bin/python3
"""spring_plate — a rigid square plate on a vertical spring, standing in for the FEM solver.

    spring_plate.py plate.json --endpoint EP --output DIR [--endpoint-file FILE]
                    [--idle-timeout SECONDS] [--fail-at STEP:ITERATION]
                    [--retryable-above DT] [--capabilities WORDS] [--no-restore]

The interface is an n × n grid of nodes over the plate joined by line elements (so the DEM's
net wall is a fine grid a sphere can rest on). All nodes share one vertical displacement w:
    M w'' + c w' + k w = F_z (sum of the nodal forces, held constant over the step)
integrated with the trapezoidal rule (Newmark γ = 1/2, β = 1/4, unconditionally stable,
no numerical damping). Static answer under a resting weight W: w = −W / k.

plate.json keys (SI units): size (edge length, m, default 1), nodes_per_side (default 11),
center ([x, y, z] of the plate, m, default [0, 0, 0]), mass (kg, default 10), stiffness (N/m,
required), damping_ratio (ζ of the plate-spring, default 0), gravity (acceleration on the
plate's own mass, m/s², default 0).
Output: DIR/plate.csv with one row per accepted step: time, w, w', F_z (created at the first
BEGIN_STEP; a RESUME reopens it cut back to the rows of the checkpoint).
Checkpoint/resume (capability "checkpoint", protocol/README.md §3.3): the committed state
w, w', w'' and the length of plate.csv, saved bit for bit by netcouple_participant.py in
DIR/checkpoint/fem_<name>.json.
--fail-at S:K replies an error to SOLVE of step S, iteration K (to test fault handling).
Switches for tests of the coupler's checks:
--retryable-above DT fails every SOLVE with dt > DT as retryable (the coupler retries the
  step with a smaller dt); --capabilities WORDS replaces the announced capabilities (default
  "restore checkpoint"; "--capabilities=" announces none); --no-restore makes every SOLVE start from
  the state the previous SOLVE ended in instead of the start of the step (a participant that
  forgets to restore; strong coupling must catch it).
"""
import argparse
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from netcouple_participant import Participant, ParticipantError, serve_until_shutdown  # noqa: E402

ALLOWED = {"size", "nodes_per_side", "center", "mass", "stiffness", "damping_ratio", "gravity",
           "comment"}


def load(path):
    try:
        with open(path) as f:
            cfg = json.load(f)
    except (OSError, ValueError) as e:
        raise SystemExit("spring_plate: %s: %s" % (path, e))
    unknown = set(cfg) - ALLOWED
    if unknown:
        raise SystemExit("spring_plate: %s: unknown key(s) %s (allowed: %s)"
                         % (path, sorted(unknown), sorted(ALLOWED)))
    if "stiffness" not in cfg or not cfg["stiffness"] > 0:
        raise SystemExit("spring_plate: %s: stiffness: expected a number > 0" % path)
    return cfg


class Plate:
    def __init__(self, cfg, output_dir, fail_at, retryable_above=None, no_restore=False):
        self.size = float(cfg.get("size", 1.0))
        self.n = int(cfg.get("nodes_per_side", 11))
        self.center = np.array(cfg.get("center", [0.0, 0.0, 0.0]), dtype=float)
        self.M = float(cfg.get("mass", 10.0))
        self.k = float(cfg["stiffness"])
        self.c = 2.0 * float(cfg.get("damping_ratio", 0.0)) * math.sqrt(self.k * self.M)
        self.g = float(cfg.get("gravity", 0.0))
        self.fail_at = fail_at
        self.retryable_above = retryable_above
        self.no_restore = no_restore
        # committed state (start of step) and trial state (end of step)
        self.w = self.v = 0.0
        self.a = self.g          # consistent initial acceleration (no load)
        self.w1, self.v1, self.a1, self.F1 = self.w, self.v, self.a, 0.0
        self.solved = False
        self.csv_path = os.path.join(output_dir, "plate.csv")
        self.csv = None       # created at the first begin_step, reopened by a resume
        self.nodes = self.n * self.n

    def interface(self, cmd):
        h = self.size / (self.n - 1)
        xs = self.center[0] - self.size / 2 + h * np.arange(self.n)
        ys = self.center[1] - self.size / 2 + h * np.arange(self.n)
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        coords = np.column_stack([X.ravel(), Y.ravel(), np.full(self.nodes, self.center[2])])
        idx = np.arange(self.nodes).reshape(self.n, self.n)
        elements = [(idx[i, j], idx[i + 1, j]) for i in range(self.n - 1) for j in range(self.n)]
        elements += [(idx[i, j], idx[i, j + 1]) for i in range(self.n) for j in range(self.n - 1)]
        return [("node_ids", np.arange(self.nodes, dtype=np.int32)),
                ("coordinates", coords),
                ("elements", np.array(elements, dtype=np.int32))], {}

    def begin_step(self, cmd):
        if self.csv is None:
            self.csv = open(self.csv_path, "w")
            self.csv.write("time,w,v,force_z\n")
            self.csv.flush()
        self.solved = False
        return [], {}

    def checkpoint_state(self, cmd):
        return {"w": self.w, "v": self.v, "a": self.a,
                "csv_bytes": self.csv.tell() if self.csv is not None else 0}

    def restore_state(self, cmd, state):
        self.w, self.v, self.a = state["w"], state["v"], state["a"]
        self.w1, self.v1, self.a1 = self.w, self.v, self.a
        self.csv = reopen_cut(self.csv_path, state["csv_bytes"])

    def solve(self, cmd):
        if self.fail_at == (cmd.step, cmd.iteration):
            raise ParticipantError("spring_plate: requested failure at step %d iteration %d"
                                   % (cmd.step, cmd.iteration))
        if self.retryable_above is not None and cmd.dt > self.retryable_above:
            raise ParticipantError("spring_plate: dt = %g s is above %g s (requested retryable "
                                   "failure)" % (cmd.dt, self.retryable_above), retryable=True)
        force = cmd.array("force", (self.nodes, 3))
        dt = cmd.dt
        if not dt > 0:
            raise ParticipantError("spring_plate: dt must be > 0, got %r" % dt)
        F = float(force[:, 2].sum()) + self.M * self.g
        # trapezoidal rule from the committed state (restores it for every iteration)
        keff = self.k + 2.0 * self.c / dt + 4.0 * self.M / dt ** 2
        rhs = F + self.M * (4.0 / dt ** 2 * self.w + 4.0 / dt * self.v + self.a) \
            + self.c * (2.0 / dt * self.w + self.v)
        w1 = rhs / keff
        v1 = 2.0 * (w1 - self.w) / dt - self.v
        a1 = 4.0 * (w1 - self.w) / dt ** 2 - 4.0 * self.v / dt - self.a
        self.w1, self.v1, self.a1, self.F1 = w1, v1, a1, F
        if self.no_restore:   # the bug this switch stands for: the trial state is kept
            self.w, self.v, self.a = w1, v1, a1
        self.solved = True
        u = np.zeros((self.nodes, 3))
        u[:, 2] = w1
        vel = np.zeros((self.nodes, 3))
        vel[:, 2] = v1
        return [("displacement", u), ("velocity", vel)], {"newton_iterations": 1,
                                                          "residual_norm": 0.0}

    def accept_step(self, cmd):
        if self.solved:
            self.w, self.v, self.a = self.w1, self.v1, self.a1
        self.csv.write("%.12g,%.12g,%.12g,%.12g\n" % (cmd.time + cmd.dt, self.w, self.v,
                                                      self.F1 if self.solved else 0.0))
        self.csv.flush()
        return [], {}

    def close(self):
        if self.csv is not None:
            self.csv.close()


def reopen_cut(path, size):
    """A result file as it was at a checkpoint: cut back to `size` bytes, then appended to."""
    try:
        f = open(path, "r+")
        f.truncate(size)
        f.seek(size)
    except OSError as e:
        raise ParticipantError("%s: cannot reopen at the checkpoint: %s" % (path, e))
    return f


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("input")
    ap.add_argument("--endpoint", required=True)
    ap.add_argument("--output", required=True)
    ap.add_argument("--endpoint-file")
    ap.add_argument("--idle-timeout", type=float, default=300.0)
    ap.add_argument("--fail-at", default=None)
    ap.add_argument("--retryable-above", type=float, default=None)
    ap.add_argument("--capabilities", default="restore checkpoint")
    ap.add_argument("--no-restore", action="store_true")
    args = ap.parse_args()
    cfg = load(args.input)
    os.makedirs(args.output, exist_ok=True)
    fail_at = tuple(int(x) for x in args.fail_at.split(":")) if args.fail_at else None
    plate = Plate(cfg, args.output, fail_at, args.retryable_above, args.no_restore)
    p = Participant(args.endpoint, "fem", "netcouple spring_plate.py", args.capabilities,
                    args.idle_timeout, args.endpoint_file, args.output)
    # exits 1 after SHUTDOWN when a command was answered with an error (protocol rule)
    return serve_until_shutdown(p, plate, "spring_plate", plate.close)


if __name__ == "__main__":
    sys.exit(main())
