"""test_standalone — bin/dem_solver on the documented examples: exit codes, the HDF5 output
layout, the XDMF file (tests/xdmf_check.py), physics of the drop example (the wall force at
rest equals the weight, within 0.1 %), and clear errors with non-zero exit for bad input and
bad command lines."""
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np

root = os.environ["NC_ROOT"]
sys.path.insert(0, os.path.join(root, "tests"))
from xdmf_check import check_xdmf, grid_counts, self_test  # noqa: E402
exe = os.path.join(os.environ["NC_BIN"], "dem_solver")
tmp = os.environ["NC_TMP"]
examples = os.path.join(root, "dem_solver", "examples")
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL:", what)


def run(args, timeout=300):
    return subprocess.run([exe] + args, capture_output=True, text=True, timeout=timeout)


# the material of the small inputs written below (opens the JSON object)
MATERIAL = ('{"materials": [{"name": "m", "youngs_modulus_pa": 1e7, "poisson_ratio": 0.2,'
            ' "density_kg_m3": 1000, "restitution": 0.5, "friction": 0.3}],')


def write(name, text):
    path = os.path.join(tmp, name)
    with open(path, "w") as f:
        f.write(text)
    return path


# 1. drop example: a rock bounces and rolls on a floor, then rests
out = os.path.join(tmp, "drop")
r = run([os.path.join(examples, "drop.json"), "--output", out])
check(r.returncode == 0, "drop.json exits 0: " + r.stderr)
with h5py.File(os.path.join(out, "dem.h5"), "r") as f:
    t = f["time"][:]
    n_out = len(t)
    check(n_out == 101, "101 output steps (0..2 s every 0.02 s), got %d" % n_out)
    check(np.allclose(f["particles/radius"][:], [0.1]), "radius dataset")
    check(f["particles/id"].dtype == np.int32, "ids are int32")
    # output at exact multiples of the interval, the last one at end_time_s exactly
    check(np.abs(t - 0.02 * np.arange(n_out)).max() < 1e-12 and t[-1] == 2.0,
          "output times k * 0.02 s up to 2 s: %s ... %s" % (t[:3], t[-2:]))
    for name, units in (("position", "m"), ("velocity", "m/s"), ("angular_velocity", "rad/s")):
        d = f["particles/" + name]
        check(d.shape == (n_out, 1, 3), "particles/%s shape %s" % (name, d.shape))
        check(d.attrs.get("units") == units.encode(), "particles/%s units %r" % (name, d.attrs.get("units")))
    no_units = []
    f.visititems(lambda name, obj: no_units.append(name)
                 if isinstance(obj, h5py.Dataset) and "units" not in obj.attrs else None)
    check(not no_units, "every dataset has a units attribute: missing on %s" % no_units)
    wall = f["walls/force"][:]
    check(wall.shape == (n_out, 2, 3), "walls/force shape (steps, planes + net, 3)")
    m = 4.0 / 3.0 * np.pi * 0.1**3 * 2500
    check(abs(-wall[-1, 0, 2] - m * 9.81) < 1e-3 * m * 9.81,
          "floor force at rest = weight (%g vs %g)" % (-wall[-1, 0, 2], m * 9.81))
    # rolling after sliding: v = 5/7 v0 (without losses in the bounces' tangential dashpot, 3 %)
    vx = f["particles/velocity"][-1, 0, 0]
    check(abs(vx - 5.0 / 7.0 * 0.5) < 0.03 * 5.0 / 7.0 * 0.5, "rolls at 5/7 v0: %g" % vx)
# particles.xdmf describes dem.h5 exactly (tests/xdmf_check.py): one Polyvertex grid per row of /time
# at that time, with the radius, id and velocity attributes; and the check fails on broken copies
xdmf_path = os.path.join(out, "particles.xdmf")
for problem in check_xdmf(xdmf_path, "/time"):
    check(False, problem)
check(grid_counts(xdmf_path) == {"particles": n_out}, "xdmf has one grid per output step: %s" % grid_counts(xdmf_path))
xdmf = ET.parse(xdmf_path).getroot()
grids = xdmf.findall(".//Grid[@GridType='Uniform']")
check(len(grids) == n_out, "xdmf has one grid per output step")
check(grids[0].find("Topology").get("TopologyType") == "Polyvertex", "Polyvertex topology")
names = [a.get("Name") for a in grids[0].findall("Attribute")]
check("radius" in names and "velocity" in names, "radius and velocity attributes: %s" % names)
for missed in self_test(out, "particles.xdmf", "/time", tmp):
    check(False, "xdmf_check self-test: " + missed)

# 2. the other examples run (short end times are set in the files)
for name in sorted(os.listdir(examples)):
    if not name.endswith(".json") or name in ("drop.json",) or name.startswith("coupled"):
        continue
    r = run([os.path.join(examples, name), "--output", os.path.join(tmp, name[:-5])])
    check(r.returncode == 0, "example %s exits 0: %s" % (name, r.stderr.strip()))

# an input without particles (walls only) is valid and runs
empty = write("empty.json", MATERIAL + ' "planes": [{"point": [0, 0, 0], "normal": [0, 0, 1]}],'
                            ' "end_time_s": 0.01}')
r = run([empty, "--output", os.path.join(tmp, "empty")])
check(r.returncode == 0, "no particles: exits 0: " + r.stderr)

# 3. errors: message names the problem, exit code non-zero
bad = write("bad.json", MATERIAL + ' "particles": [{"position": [0, 0, 0], "radius": -1}]}')
r = run([bad, "--output", os.path.join(tmp, "bad")])
check(r.returncode == 1 and "particles[0].radius" in r.stderr, "negative radius: " + r.stderr)
r = run([os.path.join(tmp, "missing.json"), "--output", os.path.join(tmp, "x")])
check(r.returncode == 1 and "missing.json" in r.stderr, "missing file: " + r.stderr)
write("bad.json", '{"materials": [}')
r = run([bad, "--output", os.path.join(tmp, "bad")])
check(r.returncode == 1 and "malformed JSON" in r.stderr, "bad JSON: " + r.stderr)
r = run([os.path.join(examples, "drop.json")])
check(r.returncode == 2 and "--output" in r.stderr, "missing --output: usage error")
r = run([os.path.join(examples, "drop.json"), "--output", tmp, "--frobnicate"])
check(r.returncode == 2, "unknown option: usage error")
# coupled mode without a net_wall material is refused before binding
r = run([os.path.join(examples, "drop.json"), "--output", os.path.join(tmp, "c"),
         "--endpoint", "tcp://127.0.0.1:*"])
check(r.returncode == 1 and "net_wall" in r.stderr, "coupled without net_wall: " + r.stderr)
# --check: the input read and checked, nothing run (no --output needed, no folder made);
# with --endpoint also what the coupled mode needs, nothing bound
out = os.path.join(tmp, "check_out")
r = run([os.path.join(examples, "drop.json"), "--check", "--output", out])
check(r.returncode == 0 and "valid (checked only, nothing run)" in r.stdout
      and not os.path.exists(out), "--check valid: %d %s %s" % (r.returncode, r.stdout, r.stderr))
r = run([os.path.join(examples, "drop.json"), "--check", "--endpoint", "tcp://127.0.0.1:*"])
check(r.returncode == 1 and "net_wall" in r.stderr, "--check --endpoint without net_wall: " + r.stderr)
write("bad_check.json", '{"materials": [], "dt": 1}')
r = run([os.path.join(tmp, "bad_check.json"), "--check"])
check(r.returncode == 1 and "bad_check.json" in r.stderr and "dt: unknown key" in r.stderr,
      "--check bad: %d %s" % (r.returncode, r.stderr))

print("%d failure(s)" % len(failures))
sys.exit(1 if failures else 0)
