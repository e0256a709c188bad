"""test_barrier_mel_inputs — cases/barrier_mel's committed inputs are what its make_case.py
writes (fem.json, dem.json, coupler.json equal as JSON, numbers to 1e-12 of the largest
magnitude in their array: the block's inertia tensor, a sum over its spheres, differs in its
last bits between CPUs, 12.294663368414161 against ...154 on its diagonal and rounding
residue of 1e-17-1e-16 off it; so that a change of make_barrier.py's or
make_ead_block.py's defaults cannot leave the committed case stale), they carry the settings
its README states (rope damping kappa 1e-4 s, Bossak alpha -0.1, a 5 cm shackle gap on every
sliding rope, a 320 kg block at 25 m/s), and fem_solver runs the barrier alone for 40 steps
of the case's Delta t under self-weight and prestress (exit 0: a step whose Newton fails ends
the run with exit 1), starting at rest in its static equilibrium and staying there. The coupled 0.3 s run takes 9 minutes and is not part of `make test`
(its README has the figures).
"""
import json
import math
import os
import subprocess

root = os.environ["NC_ROOT"]
tmp = os.environ["NC_TMP"]
exe = os.path.join(os.environ["NC_BIN"], "fem_solver")
case = os.path.join(root, "cases", "barrier_mel")
py = "/usr/bin/python3"
failures = []


def check(cond, what):
    print(("ok  " if cond else "FAIL") + ": " + what)
    if not cond:
        failures.append(what)


def largest(x):
    """the largest magnitude of the numbers (not booleans) in a JSON array, 0 if none"""
    if isinstance(x, list):
        return max((largest(y) for y in x), default=0.0)
    return abs(x) if isinstance(x, (int, float)) and not isinstance(x, bool) else 0.0


def same_json(a, b, scale=0.0):
    """a == b as JSON values, numbers (not booleans) within 1e-12 of themselves or of the
    largest magnitude in the array they are in (scale)"""
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-12 * scale)
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same_json(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        inner = scale or max(largest(a), largest(b))
        return len(a) == len(b) and all(same_json(x, y, inner) for x, y in zip(a, b))
    return a == b


out = os.path.join(tmp, "regenerated")
subprocess.run([py, os.path.join(case, "make_case.py"), "--output", out], check=True,
               stdout=subprocess.DEVNULL)
for name in ("fem.json", "dem.json", "coupler.json"):
    with open(os.path.join(case, name)) as a, open(os.path.join(out, name)) as b:
        check(same_json(json.load(a), json.load(b)),
              "%s: the committed file is what make_case.py writes" % name)

fem = json.load(open(os.path.join(case, "fem.json")))
dem = json.load(open(os.path.join(case, "dem.json")))
coupler = json.load(open(os.path.join(case, "coupler.json")))
check(coupler["tolerance"] == 1e-6 and coupler.get("work_tolerance") == 1e-6
      and coupler.get("newton_estimate") == 0.1,
      "tolerance 1e-6 with the work test, work_tolerance 1e-6, and newton_estimate 0.1: %s, %s, %s"
      % (coupler["tolerance"], coupler.get("work_tolerance"), coupler.get("newton_estimate")))
check(fem["rayleigh"] == {"tau_per_s": 2.0, "kappa_s": 1e-4}, "Rayleigh tau 2 /s, kappa 1e-4 s: %s" % fem["rayleigh"])
check(fem["analysis"]["integrator"] == "bossak" and fem["analysis"]["alpha_b"] == -0.1,
      "Bossak alpha -0.1: %s" % fem["analysis"])
gaps = {s["name"]: s.get("shackle_gap_m") for s in fem["element_sets"] if s["type"] == "sliding_cable"}
check(len(gaps) == 3 and all(g == 0.05 for g in gaps.values()), "5 cm shackle gap on the sliding ropes: %s" % gaps)
block = dem["clusters"][0]
speed = math.sqrt(sum(v * v for v in block["velocity"]))
check(abs(block["mass_kg"] - 320.0) < 0.5 and abs(speed - 25.0) < 1e-9,
      "block %.1f kg at %.3f m/s" % (block["mass_kg"], speed))

# the barrier alone: 40 steps of the case's dt from rest under self-weight and prestress
short = dict(fem, analysis=dict(fem["analysis"], end_time_s=40 * fem["analysis"]["dt_s"]))
path = os.path.join(tmp, "barrier_alone.json")
json.dump(short, open(path, "w"))
run = subprocess.run([exe, path, "--output", os.path.join(tmp, "alone")], capture_output=True, text=True)
summary = [l for l in (run.stdout + run.stderr).splitlines()
           if " steps, " in l and "Newton iterations" in l and "started at rest" not in l]
settled = [l for l in (run.stdout + run.stderr).splitlines() if "started at rest in static equilibrium" in l]
check(fem["analysis"].get("initial_state") == "static" and len(settled) == 1,
      "the barrier starts at rest in static equilibrium (analysis.initial_state): %s" % settled[:1])
if run.returncode == 0:
    import h5py
    import numpy as np
    with h5py.File(os.path.join(tmp, "alone", "fem.h5"), "r") as f:
        u = np.array(f["/output/displacement"])
    moved = float(np.abs(u - u[0]).max())
    sag = float(np.linalg.norm(u[0], axis=1).max())
    check(sag > 0.05 and moved < 1e-6,
          "and hangs still: sagged %.3f m from the generated geometry, then moved %.2g m in 40 "
          "steps (at most 1e-6 m)" % (sag, moved))
check(run.returncode == 0 and len(summary) == 1 and " 40 steps, " in summary[0],
      "fem_solver runs the barrier alone for 40 steps (a failed Newton solve exits 1) "
      "(exit %d): %s" % (run.returncode, summary[:1] or run.stderr.strip().splitlines()[-1:]))

print("%d failure(s)" % len(failures))
raise SystemExit(1 if failures else 0)
