#!/usr/bin/python3
"""ball_dem — one sphere with a linear spring-dashpot contact on a flat interface, standing in
for the DEM solver (tests of the coupler without the real dem_solver).

    ball_dem.py ball.json --endpoint EP --output DIR [--endpoint-file FILE]
                [--idle-timeout SECONDS]

The interface is treated as the horizontal plane at the mean height of its nodes (fine for
the rigid spring_plate.py). Each SOLVE restores the start-of-step state, moves the plane
linearly from its start-of-step height to the given end-of-step height over `substeps`
symplectic-Euler sub-steps and returns the time-averaged contact force on the plane, shared
equally by the nodes (values near_interface, min_gap_m, contacts, substeps).
ball.json keys (SI): radius (default 0.1), mass (default 1), position ([x, y, z] of the
centre, required), velocity (default [0, 0, 0]), stiffness (contact, N/m, default 1e5),
damping_ratio (contact, default 0.2), gravity (m/s², default -9.81), substeps (default 20),
near_distance (gap below which near_interface = 1, m, default 0.05).
Output: DIR/ball.csv with one row per accepted step: time, z, vz, gap (created at the first
BEGIN_STEP; a RESUME reopens it cut back to the rows of the checkpoint).
Checkpoint/resume (capability "checkpoint", protocol/README.md §3.3): the committed z, vz,
plane displacement and the length of ball.csv, saved bit for bit by netcouple_participant.py
in DIR/checkpoint/dem_<name>.json.
"""
import argparse
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from netcouple_participant import Participant, ParticipantError, serve_until_shutdown  # noqa: E402
from spring_plate import reopen_cut  # noqa: E402

ALLOWED = {"radius", "mass", "position", "velocity", "stiffness", "damping_ratio", "gravity",
           "substeps", "near_distance", "comment"}


class Ball:
    def __init__(self, cfg, output_dir):
        self.R = float(cfg.get("radius", 0.1))
        self.m = float(cfg.get("mass", 1.0))
        self.z = float(cfg["position"][2])
        self.vz = float(cfg.get("velocity", [0, 0, 0])[2])
        self.k = float(cfg.get("stiffness", 1e5))
        self.c = 2.0 * float(cfg.get("damping_ratio", 0.2)) * math.sqrt(self.k * self.m)
        self.g = float(cfg.get("gravity", -9.81))
        self.substeps = int(cfg.get("substeps", 20))
        self.near = float(cfg.get("near_distance", 0.05))
        self.plane0 = None        # reference height of the plane
        self.wall = 0.0           # committed plane displacement (start of step)
        self.trial = None
        self.nodes = 0
        self.csv_path = os.path.join(output_dir, "ball.csv")
        self.csv = None       # created at the first begin_step, reopened by a resume

    def interface(self, cmd):
        coords = cmd.array("coordinates")
        if coords.ndim != 2 or coords.shape[1] != 3:
            raise ParticipantError("coordinates must be [n, 3]")
        self.nodes = coords.shape[0]
        self.plane0 = float(coords[:, 2].mean())
        return [], {}

    def begin_step(self, cmd):
        if self.csv is None:
            self.csv = open(self.csv_path, "w")
            self.csv.write("time,z,vz,gap\n")
            self.csv.flush()
        self.trial = None
        return [], {}

    def checkpoint_state(self, cmd):
        return {"z": self.z, "vz": self.vz, "wall": self.wall,
                "csv_bytes": self.csv.tell() if self.csv is not None else 0}

    def restore_state(self, cmd, state):
        self.z, self.vz, self.wall = state["z"], state["vz"], state["wall"]
        self.trial = None
        self.csv = reopen_cut(self.csv_path, state["csv_bytes"])

    def close(self):
        if self.csv is not None:
            self.csv.close()

    def solve(self, cmd):
        if self.plane0 is None:
            raise ParticipantError("ball_dem: SOLVE before INTERFACE")
        u = cmd.array("displacement", (self.nodes, 3))
        cmd.array("velocity", (self.nodes, 3))
        w_end = float(u[:, 2].mean())
        dt = cmd.dt / self.substeps
        z, vz = self.z, self.vz
        impulse = 0.0
        contacts = 0
        for i in range(self.substeps):
            wall = self.wall + (w_end - self.wall) * (i + 1) / self.substeps
            wall_v = (w_end - self.wall) / cmd.dt
            overlap = self.plane0 + wall + self.R - z
            f = 0.0
            if overlap > 0:
                f = max(0.0, self.k * overlap - self.c * (vz - wall_v))
            vz += dt * (f / self.m + self.g)
            z += dt * vz
            impulse += f * dt
        gap = z - self.R - (self.plane0 + w_end)
        contacts = 1 if gap < 0 else 0
        self.trial = (z, vz, w_end, gap)
        force = np.zeros((self.nodes, 3))
        force[:, 2] = -impulse / cmd.dt / self.nodes   # on the plate: downwards
        return [("force", force)], {"near_interface": 1 if gap < self.near else 0,
                                    "min_gap_m": gap, "contacts": contacts,
                                    "substeps": self.substeps}

    def accept_step(self, cmd):
        if self.trial is not None:
            self.z, self.vz, self.wall, gap = self.trial
            self.csv.write("%.12g,%.12g,%.12g,%.12g\n" % (cmd.time + cmd.dt, self.z, self.vz, gap))
            self.csv.flush()
        return [], {}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("input")
    ap.add_argument("--endpoint", required=True)
    ap.add_argument("--output", required=True)
    ap.add_argument("--endpoint-file")
    ap.add_argument("--idle-timeout", type=float, default=300.0)
    args = ap.parse_args()
    try:
        with open(args.input) as f:
            cfg = json.load(f)
    except (OSError, ValueError) as e:
        raise SystemExit("ball_dem: %s: %s" % (args.input, e))
    unknown = set(cfg) - ALLOWED
    if unknown or "position" not in cfg:
        raise SystemExit("ball_dem: %s: unknown keys %s or missing position" % (args.input,
                                                                             sorted(unknown)))
    os.makedirs(args.output, exist_ok=True)
    ball = Ball(cfg, args.output)
    p = Participant(args.endpoint, "dem", "netcouple ball_dem.py", "restore checkpoint",
                    args.idle_timeout, args.endpoint_file, args.output)
    return serve_until_shutdown(p, ball, "ball_dem", ball.close)


if __name__ == "__main__":
    sys.exit(main())
