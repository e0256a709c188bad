#!/usr/bin/python3
"""make_case.py — writes this case's fem.json, dem.json and coupler.json (README.md says why
each value is what it is). Run from anywhere:

    /usr/bin/python3 cases/barrier_mel/make_case.py [--dt DT] [--end-time T] [--output DIR]

The barrier comes from scripts/make_barrier.py and the block from scripts/make_ead_block.py;
this script only chooses their parameters, aims the block and sets the coupling.
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
PY = "/usr/bin/python3"

# a 100 kJ class barrier (EAD 340059 energy class 0: MEL 100 kJ): three modules of 10 m, 3 m
# posts, an 8 mm wire-rope net at 0.3 m meshes, make_barrier's ropes, brakes and shackle gap;
# rope damping kappa 1e-4 s with Bossak alpha -0.1, so the net's high modes are damped by the
# ropes rather than by the integrator (docs/notes/shackle_contact.md)
BARRIER = ["--modules", "3", "--spacing", "10", "--height", "3", "--mesh-size", "0.3",
           "--rayleigh-tau", "2", "--rayleigh-kappa", "1e-4", "--alpha-b", "-0.1"]
ENERGY_KJ, SPEED = 100.0, 25.0           # MEL 100 kJ at the EAD's minimum 25 m/s: 320 kg
CLEARANCE_M = 0.5                        # block centre before the net centre (contact at ~14 ms)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dt", type=float, default=2.5e-4, help="coupling step (s)")
    ap.add_argument("--end-time", type=float, default=0.3, help="end of the run (s)")
    ap.add_argument("--output", default=HERE, help="folder to write into (default: this case)")
    a = ap.parse_args()
    os.makedirs(a.output, exist_ok=True)
    fem_path = os.path.join(a.output, "fem.json")
    subprocess.run([PY, os.path.join(ROOT, "scripts", "make_barrier.py")] + BARRIER
                   + ["--dt", "%g" % a.dt, "--end-time", "%g" % a.end_time, "--output", fem_path,
                      "--summary", os.path.join(a.output, "barrier.md")],
                   check=True, stdout=subprocess.DEVNULL)
    fem = json.load(open(fem_path))
    centre = np.array(fem["nodes"][fem["node_sets"]["net_centre"][0]])
    tilt = np.radians(10.0)                              # make_barrier's default post tilt
    normal = np.array([0.0, np.cos(tilt), -np.sin(tilt)])   # net normal, downslope
    position = centre - CLEARANCE_M * normal
    dem_path = os.path.join(a.output, "dem.json")
    subprocess.run([PY, os.path.join(ROOT, "scripts", "make_ead_block.py"),
                    "--energy-kj", "%g" % ENERGY_KJ, "--speed", "%g" % SPEED,
                    "--restitution", "0.25", "--sphere-radius", "0.25", "--spacing", "1.0",
                    "--position"] + ["%.6f" % x for x in position]
                   + ["--direction"] + ["%.9f" % x for x in normal] + ["--output", dem_path],
                   check=True, stdout=subprocess.DEVNULL)
    dem = json.load(open(dem_path))
    dem["description"] = ("MEL test: %g kJ at %g m/s along the net normal, aimed at the middle module's "
                          "centre; written by make_case.py. %s" % (ENERGY_KJ, SPEED, dem.get("description", "")))
    dem["net_wall"] = {"youngs_modulus_pa": 1e11, "poisson_ratio": 0.3, "friction": 0.5,
                       "restitution": 0.25, "cable_radius_m": 0.004}
    dem["gravity"] = [0, 0, -9.81]
    # the DEM sub-step below the coupler's reduced steps (down to dt/512): with the automatic
    # 2.4e-5 s a reduced step is shorter than one sub-step and a net node moving into the
    # block is found deep inside it (tests/cases/test_barrier_small.sh)
    dem["dt_s"] = 2e-6
    dem["output_interval_s"] = 0.005
    json.dump(dem, open(dem_path, "w"), indent=1)
    # the work test and the Newton error estimate (coupler/README.md "Interface Jacobian"):
    # the same results to the README's digits with a sixth and then a fifth fewer interface
    # iterations (docs/notes/interface_jacobian.md)
    coupler = {"comment": "MEL test of a three-module 100 kJ barrier: strong coupling with the interface "
                          "Jacobian, Aitken from the full step, the work test and the Newton error "
                          "estimate; written by make_case.py",
               "scheme": "strong", "dt": a.dt, "end_time": a.end_time, "tolerance": 1e-6,
               "work_tolerance": 1e-6, "newton_estimate": 0.1,
               "max_iterations": 30, "step_control": {"dt_min": a.dt / 512},
               "relaxation": {"method": "aitken", "alpha": 1.0, "first_iteration_cap": 1.0},
               "relaxed_quantity": "displacement_velocity",
               "output": {"progress_interval": 5}}
    json.dump(coupler, open(os.path.join(a.output, "coupler.json"), "w"), indent=1)
    print("make_case: %s: fem.json (%d nodes), dem.json (%g kJ block), coupler.json (dt %g s, to %g s)"
          % (a.output, len(fem["nodes"]), ENERGY_KJ, a.dt, a.end_time))
    return 0


if __name__ == "__main__":
    sys.exit(main())
