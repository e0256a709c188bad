"""test_report — scripts/report.py on short real runs: the numbers it prints against an
independent computation from the HDF5 files and against free fall, and its verdicts.

Runs (about 10 s of wall time together on an idle machine):
  rebound   tests/coupler/cases/small_net (18 kg rock, 1.35 m/s onto a 1.2 m net), COR 1,
            cables E 1e10 Pa, centred coupling (no energy created), 0.22 s, DEM and FEM output
            every 2 ms: verdict "rebounded" with an apparent restitution in (0.5, 1];
  stopping  cases/rest_position as `make demo` runs it (253 kg sphere dropped 0.30 m onto the
            cable, COR 0.5, strong coupling at 3e-2 s, 8 s): verdict "stopped";
  no contact  small_net with the rock beside the net: verdict "no contact";
  plus a FEM-only folder (report written, dem.h5 named as missing) and folders that are not
  runs (exit 2 with a message).
Tolerances (stated at each check): impact speed within 0.5 % (rebound: 1 ms steps) and 1 %
(stopping: 30 ms steps) of sqrt(v0^2 + 2 g h); the rest against the HDF5 files to the six
printed digits (relative 1e-5) or, for braking distance and time, within the DEM output
spacing's interpolation error (0.5 mm / 2 ms; 3 mm / 10 ms).
"""
import json
import os
import re
import shutil
import subprocess
import sys

import h5py
import numpy as np

root = os.environ["NC_ROOT"]
tmp = os.environ["NC_TMP"]
py = os.environ.get("PYTHON", "/usr/bin/python3")
failures = []
G = 9.81


def check(cond, what):
    print(("ok:   " if cond else "FAIL: ") + what)
    if not cond:
        failures.append(what)


def near(a, b, tol, what, rel=False):
    err = abs(a - b) / abs(b) if rel else abs(a - b)
    check(err <= tol, "%s: %.6g against %.6g (%s %.3g, tolerance %.3g)"
          % (what, a, b, "relative error" if rel else "error", err, tol))


def run_case(name, case, sets):
    out = os.path.join(tmp, name)
    cmd = [os.path.join(root, "scripts", "run_case.sh"), os.path.join(root, case), "--out", out, "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    if p.returncode not in (0, 3):
        print(p.stdout, p.stderr)
        sys.exit("run_case.sh %s failed (exit %d)" % (case, p.returncode))
    return out


def report(folder, *extra):
    p = subprocess.run([py, os.path.join(root, "scripts", "report.py"), folder] + list(extra),
                       capture_output=True, text=True, timeout=120)
    return p


def parsed(p):
    """stdout "key: value" lines -> dict of key -> list of the numbers in the value (and text)."""
    d = {}
    for line in p.stdout.splitlines():
        k, _, v = line.partition(": ")
        nums = [float(x) for x in re.findall(r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?", v)]
        d[k] = (nums, v)
    return d


def num(d, key, i):
    return d[key][0][i]


def h5_truth(folder):
    """Independent numbers from the HDF5 files."""
    t = {}
    with h5py.File(os.path.join(folder, "fem.h5"), "r") as f:
        af = f["/output/axial_force"][:]
        t["force"] = af.max()
        t["force_el"] = int(np.unravel_index(np.argmax(af), af.shape)[1])
        R = f["/output/reaction"][:]
        t["res"] = np.linalg.norm(R.sum(axis=1), axis=1).max()
        t["single"] = np.linalg.norm(R, axis=2).max()
        t["defl"] = float(f["/output/displacement"].attrs["max_magnitude"])
    with h5py.File(os.path.join(folder, "coupling.h5"), "r") as f:
        t["input"] = f["/energy/input"][-1]
        t["created_max"] = f["/energy/created"][:].max()
        t["diss_fem"] = f["/energy/fem_dissipated"][:].sum()
        t["diss_dem"] = f["/energy/dem_dissipated"][:].sum()
        F = np.linalg.norm(f["/steps/contact_force"][:], axis=1)
        t["step_end"] = f["/steps/time"][:]
        t["F"] = F
    with h5py.File(os.path.join(folder, "dem.h5"), "r") as f:
        t["time"] = f["/time"][:]
        t["z"] = f["/particles/position"][:, 0, 2]
        t["vz"] = f["/particles/velocity"][:, 0, 2]
        t["radius"] = f["/particles/radius"][0]
    return t


def common_checks(name, d, t, folder):
    near(num(d, "rope force", 0), t["force"], 1e-5, name + ": peak rope force (N)", rel=True)
    check(int(num(d, "rope force", 1)) == t["force_el"], name + ": element of the peak rope force %d" % t["force_el"])
    near(num(d, "reaction", 0), t["res"], 1e-5, name + ": peak resultant reaction (N)", rel=True)
    near(num(d, "reaction", 2), t["single"], 1e-5, name + ": peak single reaction (N)", rel=True)
    near(num(d, "deflection", 0), t["defl"], 1e-5, name + ": peak deflection (m)", rel=True)
    near(num(d, "energy", 0), t["input"], 1e-5, name + ": input energy (J)", rel=True)
    near(num(d, "energy", 1), t["created_max"], 1e-5 * t["input"], name + ": largest created energy (J)")
    near(num(d, "energy", 3), t["diss_fem"], 1e-5, name + ": energy dissipated by the FEM (J)", rel=True)
    near(num(d, "energy", 4), t["diss_dem"], 1e-5 * t["input"], name + ": energy dissipated by the DEM (J)")
    md = os.path.join(folder, "report.md")
    check(os.path.exists(md), name + ": report.md written")
    for png in ("rock", "net", "reactions", "energy", "iterations"):
        check(os.path.getsize(os.path.join(folder, "report", png + ".png")) > 1000, name + ": report/%s.png" % png)


def free_fall(d, name, z0, v0, R, rho, tol):
    h = z0 - R  # the cable surface is at z = 0 (no cable radius, no self-weight: the net is flat)
    v_ff = np.sqrt(v0 ** 2 + 2 * G * h)
    near(num(d, "impact", 1), v_ff, tol, name + ": impact speed against sqrt(v0^2 + 2 g h) (m/s)", rel=True)
    m = 4.0 / 3.0 * np.pi * R ** 3 * rho
    near(num(d, "rock", 2), m, 1e-5, name + ": rock mass 4/3 pi R^3 rho (kg)", rel=True)
    vi = num(d, "impact", 1)
    near(num(d, "impact", 2), 0.5 * m * vi ** 2, 1e-5, name + ": impact energy 1/2 m v^2 (J)", rel=True)
    t_ff = (-v0 + v_ff) / G
    return t_ff, R  # time and centre height of the first contact


def braking_checks(d, t, name, t_contact, z_contact, dz_tol, dt_tol):
    # independent: the vertical drop's braking ends at the lowest point of the rock's centre
    k = int(np.argmax(t["time"] > t_contact))
    j = k + int(np.argmin(t["z"][k:]))
    # the first minimum after contact (the rock may bounce several times)
    for i in range(k + 1, len(t["z"])):
        if t["vz"][i] >= 0:
            j = i if abs(t["vz"][i]) < abs(t["vz"][i - 1]) else i - 1
            break
    near(num(d, "braking", 0), z_contact - t["z"][j], dz_tol, name + ": braking distance (m): contact height - lowest centre")
    near(num(d, "braking", 2), t["time"][j] - t_contact, dt_tol, name + ": braking time (s)")


# ---- rebound: COR 1, stiff cables, centred coupling
case = "tests/coupler/cases/small_net"
cfg = json.load(open(os.path.join(root, case, "dem.json")))
rb = run_case("rebound", case, [
    "dem.materials.0.restitution=1.0", "fem.element_sets.0.youngs_modulus_pa=1e10",
    "dem.net_wall.wall_position=middle", "fem.analysis.coupling_load=step_constant",
    "coupler.end_time=0.22", "fem.analysis.end_time_s=0.22",
    "dem.output_interval_s=0.002", "fem.output.interval_steps=2",
    "fem.element_sets.0.breaking_load_n=4000"])
p = report(rb)
print(p.stdout, p.stderr)
check(p.returncode == 0, "rebound: report.py exit 0")
d = parsed(p)
t = h5_truth(rb)
common_checks("rebound", d, t, rb)
# the every-step rope peak and the breaking load, against fem.h5 /element_sets
with h5py.File(os.path.join(rb, "fem.h5"), "r") as f:
    peaks = f["/element_sets/peak_axial_force"][:]
    exceeded = int(f["/element_sets/exceeded_elements"][0])
    overload = f.attrs.get("overload", b"")
near(num(d, "rope force every step", 0), peaks.max(), 1e-5, "rebound: every-step peak rope force (N)", rel=True)
check(num(d, "rope force every step", 0) >= num(d, "rope force", 0) * (1 - 1e-9),
      "rebound: the every-step peak is at least the output steps' one")
check(int(num(d, "breaking load", 2)) == exceeded,
      "rebound: elements above the breaking load %d (fem.h5: %d)" % (int(num(d, "breaking load", 2)), exceeded))
with open(os.path.join(rb, "report.md")) as fh:
    said = "Ropes above their breaking load" in fh.read()
check(said == (exceeded > 0) == bool(overload),
      "rebound: report.md names the ropes above their breaking load exactly when fem.h5 does (%d)" % exceeded)
part = cfg["particles"][0]
tc, zc = free_fall(d, "rebound", part["position"][2], -part["velocity"][2], part["radius"],
                   cfg["materials"][0]["density_kg_m3"], 5e-3)
near(num(d, "impact", 0), tc, 1.5e-3, "rebound: impact time against free fall (s)")
braking_checks(d, t, "rebound", tc, zc, 5e-4, 2e-3)
check(d["verdict"][1].startswith("rebounded"), "rebound: verdict rebounded (%s)" % d["verdict"][1])
# rebound speed: the first DEM output after the last contact step, back to that step's end
last = np.where(t["F"] > 0)[0][-1]
t_end = t["step_end"][last]
k = int(np.argmax(t["time"] >= t_end))
v_leave = t["vz"][k] + G * (t["time"][k] - t_end)
near(num(d, "verdict", 0), v_leave, 0.01, "rebound: rebound speed (m/s) from dem.h5 after the last contact")
e = num(d, "verdict", 2)
check(0.5 < e <= 1.0, "rebound: apparent restitution %.3f in (0.5, 1] (COR 1, Rayleigh-damped net)" % e)
check("results are reliable" in d["reliability"][1], "rebound: coupler's reliability line quoted")

# ---- stopping: the demo's run
sp = run_case("stopping", "cases/rest_position", [
    "coupler.dt=3e-2", "fem.analysis.dt_s=3e-2", "coupler.end_time=8", "fem.analysis.end_time_s=8",
    "dem.materials.0.restitution=0.5"])
p = report(sp)
print(p.stdout, p.stderr)
check(p.returncode == 0, "stopping: report.py exit 0")
d = parsed(p)
t = h5_truth(sp)
common_checks("stopping", d, t, sp)
cfg2 = json.load(open(os.path.join(root, "cases/rest_position/dem.json")))
part = cfg2["particles"][0]
tc, zc = free_fall(d, "stopping", part["position"][2], 0.0, part["radius"],
                   cfg2["materials"][0]["density_kg_m3"], 1e-2)
braking_checks(d, t, "stopping", num(d, "impact", 0), zc, 3e-3, 1e-2)
check(d["verdict"][1].startswith("stopped"), "stopping: verdict stopped (%s)" % d["verdict"][1])

# ---- no contact: the rock falls beside the net
nc = run_case("nocontact", case, ["dem.particles.0.position=[3.0, 0.0, 0.2]", "coupler.end_time=0.1",
                                  "fem.analysis.end_time_s=0.1"])
p = report(nc)
print(p.stdout, p.stderr)
d = parsed(p)
check(p.returncode == 0 and d["verdict"][1].startswith("no contact"), "no contact: verdict no contact")

# ---- a FEM-only folder and folders that are not runs
fo = os.path.join(tmp, "femonly")
os.makedirs(fo)
shutil.copy(os.path.join(rb, "fem.h5"), fo)
p = report(fo)
check(p.returncode == 0 and "dem.h5 is missing" in open(os.path.join(fo, "report.md")).read(),
      "FEM-only folder: report written, dem.h5 named as missing")
empty = os.path.join(tmp, "empty")
os.makedirs(empty)
p = report(empty)
check(p.returncode == 2 and "not a run folder" in p.stderr, "empty folder: exit 2, 'not a run folder' (%s)" % p.stderr.strip())
with open(os.path.join(empty, "coupling.h5"), "w") as fh:
    fh.write("not HDF5")
p = report(empty)
check(p.returncode == 2 and "coupling.h5: cannot be read" in p.stderr, "unreadable coupling.h5: exit 2, named (%s)" % p.stderr.strip())

if failures:
    print("%d check(s) failed" % len(failures))
    sys.exit(1)
print("all checks passed")
