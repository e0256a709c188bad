"""test_barrier_report — scripts/barrier_report.py on a run folder written by hand: a real
make_barrier.py model (fem.json) with fem.h5, dem.h5 and coupling.h5 holding chosen values,
(with the FEM's every-step peak forces against the breaking loads in /element_sets),
so that every printed figure has a known answer (exact up to the JSON's float round trip,
checked to 1e-12 relative; the braking time's linear interpolation by hand). Then folders
that lack a file or are not a barrier: exit 2 with a message naming the file. A block released
at rest: the impact is taken at its first contact with the net; a block that never reaches it:
exit 2 saying so.
The coupled end-to-end run is tests/cases/test_barrier_small.sh.
"""
import json
import os
import shutil
import subprocess

import h5py
import numpy as np

root = os.environ["NC_ROOT"]
tmp = os.environ["NC_TMP"]
py = "/usr/bin/python3"
script = os.path.join(root, "scripts", "barrier_report.py")


def close(a, b, what, rel=1e-12):
    assert abs(a - b) <= rel * max(abs(b), 1e-300), "%s: %r, expected %r" % (what, a, b)


run = os.path.join(tmp, "run")
os.makedirs(run, exist_ok=True)
subprocess.run([py, os.path.join(root, "scripts", "make_barrier.py"), "--modules", "1", "--spacing", "4",
                "--height", "3", "--mesh-size", "1.0", "--output", os.path.join(run, "fem.json")],
               check=True, capture_output=True)
model = json.load(open(os.path.join(run, "fem.json")))
sets = model["node_sets"]
coords = np.array(model["nodes"], dtype=float)
nn = len(coords)
names = [s["name"] for s in model["element_sets"]]
elements = np.array([e["nodes"][:2] for e in model["elements"]])
eset = np.array([names.index(e["set"]) for e in model["elements"]], dtype=np.int32)
supports = sorted(sets["anchors"] + sets["post_bases"])
d = np.array([0.0, 0.8, -0.6])                          # impact direction (unit)
centre = sets["net_centre"][0]
other = [n for n in sets["net"] if n != centre][3]

# fem.h5: three output steps
t_out = np.array([0.0, 0.1, 0.2])
u = np.zeros((3, nn, 3))
u[1, other] = 0.8 * d                                   # largest net elongation 0.8 m at 0.1 s
u[2, centre] = 0.3 * d
top = sorted(set(elements[eset == names.index("top_rope")].ravel().tolist()) - set(supports))
base_z = coords[sets["post_bases"], 2].mean()
nominal = coords[sets["post_tops"], 2].mean() - base_z
low = top[len(top) // 2]
u[2, low, 2] = 0.55 * nominal - (coords[low, 2] - base_z)   # lowest top-rope node at 55 %
for n in top:
    if n != low:
        u[2, n, 2] = 0.9 * nominal - (coords[n, 2] - base_z)
axial = np.zeros((3, len(eset)))
peaks = {}
for i, name in enumerate(names):
    idx = np.nonzero(eset == i)[0]
    peaks[name] = 1000.0 * (i + 1)
    axial[1, idx[0]] = -peaks[name] if i % 2 else peaks[name]
reaction = np.zeros((3, len(supports), 3))
reaction[1, supports.index(sets["anchors"][2])] = [3e4, 4e4, 0.0]     # 50 kN
reaction[2, supports.index(sets["post_bases"][0])] = [0.0, 6e4, 8e4]  # 100 kN
diss = np.zeros((3, len(eset)))
brakes = np.nonzero(eset == names.index("brake_support"))[0]
diss[2, brakes[0]], diss[2, brakes[1]] = 1000.0, 234.5
mt = np.linspace(0.0, 0.2, 201)
mon_ids = [centre] + sets["post_tops"]
mdisp = np.zeros((len(mt), len(mon_ids), 3))
mdisp[:, 0] = np.outer(0.75 * np.sin(np.pi * mt / 0.24), d)   # largest 0.75 m at 0.12 s
# /element_sets (fem_solver's every-step peaks): every set with a breaking load peaks at
# 0.8 of it, except the first, at 1.77 of it with 12 elements above it from 0.031 s on
brk = np.array([s.get("breaking_load_n", 0.0) for s in model["element_sets"]])
roped = [i for i in range(len(names)) if brk[i] > 0]
over = roped[0]
ratio = np.where(np.arange(len(names)) == over, 1.77, 0.8)
es_count = np.where(np.arange(len(names)) == over, 12, 0).astype(np.int32)
es_first = np.where(np.arange(len(names)) == over, 0.031, -1.0)
es_where = np.array([np.nonzero(eset == i)[0][0] for i in range(len(names))], dtype=np.int32)
with h5py.File(os.path.join(run, "fem.h5"), "w") as f:
    f["mesh/coordinates"] = coords
    f["mesh/elements"] = elements
    f["mesh/element_set"] = eset
    f["mesh/support_nodes"] = np.array(supports, dtype=np.int32)
    f["output/time"] = t_out
    f["output/displacement"] = u
    f["output/position"] = coords[None] + u
    f["output/axial_force"] = axial
    f["output/reaction"] = reaction
    f["output/element_dissipated_energy"] = diss
    f["monitor/node_ids"] = np.array(mon_ids, dtype=np.int32)
    f["monitor/time"] = mt
    f["monitor/displacement"] = mdisp
    f["element_sets/breaking_load"] = brk
    f["element_sets/peak_axial_force"] = ratio * brk
    f["element_sets/peak_time"] = np.full(len(names), 0.052)
    f["element_sets/peak_element"] = es_where
    f["element_sets/exceeded_elements"] = es_count
    f["element_sets/first_exceedance_time"] = es_first

# dem.h5: the block's two spheres; velocity along d 12, 6, -2, -3 m/s
t_dem = np.array([0.0, 0.05, 0.1, 0.15])
va = np.array([12.0, 6.0, -2.0, -3.0])
side = np.array([0.1, 0.0, 0.0])
vel = np.stack([np.outer(va, d) + side, np.outer(va, d) - side], axis=1)
with h5py.File(os.path.join(run, "dem.h5"), "w") as f:
    f["time"] = t_dem
    f["particles/body"] = np.array([0, 0], dtype=np.int32)
    f["particles/velocity"] = vel

# coupling.h5: 10 steps of 1 ms, contact from step 3 (t 2-3 ms) on
n = 10
ct = 0.001 * np.arange(1, n + 1)
inc = (np.arange(n) >= 2).astype(np.int32)
dk = np.linspace(30000.0, 9000.0, n)
with h5py.File(os.path.join(run, "coupling.h5"), "w") as f:
    f["steps/time"] = ct
    f["steps/dt"] = np.full(n, 0.001)
    f["steps/in_contact"] = inc
    f["steps/converged"] = np.ones(n, dtype=np.int32)
    f["energy/dem_kinetic"] = dk
    f["energy/fem_kinetic"] = np.full(n, 40.0)
    f["energy/fem_elastic"] = np.full(n, 700.0)
    f["energy/fem_dissipated"] = np.full(n, 150.0)          # 1500 J in all
    f["energy/dem_dissipated"] = np.full(n, 20.0)           # 200 J: 40 J before the contact
    f["energy/dem_potential"] = np.linspace(0.0, 900.0, n)  # climbing 100 J per step
    f["energy/interface_created"] = np.full(n, -1.0)
    f["energy/created"] = np.linspace(0.0, -50.0, n)
    f["energy/limit"] = np.full(n, 300.0)
    f["energy/above"] = np.zeros(n, dtype=np.int32)

out = subprocess.run([py, script, run, "--json", os.path.join(tmp, "r.json"),
                      "--plot", os.path.join(tmp, "r.png")], capture_output=True, text=True)
print(out.stdout, out.stderr)
assert out.returncode == 0, out.returncode
r = json.load(open(os.path.join(tmp, "r.json")))
close(r["impact_speed_m_s"], 12.0, "impact speed (the spheres' mean: the side velocities cancel)")
close(r["first_contact_s"], 0.002, "first contact")
close(r["max_net_elongation_m"], 0.8, "net elongation")
assert r["max_net_elongation_node"] == other and r["max_net_elongation_time_s"] == 0.1
dd = np.array(r["impact_direction"])
close(r["max_centre_elongation_m"], float((mdisp[:, 0] @ dd).max()), "centre elongation")
close(r["max_centre_elongation_time_s"], 0.12, "centre elongation time", 1e-9)
at_hit = 0.75 * np.sin(np.pi * 0.002 / 0.24)            # monitor sample at the first contact
close(r["centre_at_contact_m"], at_hit, "net centre at the first contact", 1e-9)
close(r["max_centre_elongation_from_contact_m"], float((mdisp[:, 0] @ dd).max()) - at_hit,
      "centre elongation from the first contact", 1e-9)
vd = vel.mean(axis=1) @ dd                              # 12, 6, -2, -3 (side cancels)
t_stop = 0.05 + 0.05 * vd[1] / (vd[1] - vd[2])
close(r["block_stop_s"], t_stop, "stop time")
close(r["braking_time_s"], t_stop - 0.002, "braking time")
close(r["residual_height_ratio"], 0.55, "residual height", 1e-9)
close(r["nominal_height_m"], nominal, "nominal height")
for name, p in peaks.items():
    close(r["peak_axial_force"][name]["peak_axial_force_n"], p, "peak force " + name)
close(r["peak_anchor_reaction_n"], 5e4, "anchor reaction")
assert len(roped) >= 2 and sorted(r["overload"]) == sorted(names[i] for i in roped), r["overload"]
for i in roped:
    v = r["overload"][names[i]]
    close(v["breaking_load_n"], brk[i], "breaking load " + names[i])
    close(v["ratio"], ratio[i], "overload ratio " + names[i])
    close(v["peak_axial_force_n"], ratio[i] * brk[i], "every-step peak " + names[i])
    assert v["peak_element"] == es_where[i] and v["peak_time_s"] == 0.052
    assert v["exceeded_elements"] == es_count[i]
    assert v["first_exceedance_s"] == (0.031 if i == over else None)
assert ("%s" % names[over]) in out.stdout and "12 elements EXCEEDED" in out.stdout and "= 1.77x" in out.stdout
assert "forces beyond the breaking load are not physical" in out.stdout
close(r["peak_post_base_reaction_n"], 1e5, "post base reaction")
e = r["energy"]
close(e["block_kinetic_at_contact_j"], dk[1], "kinetic at contact")
close(e["block_kinetic_end_j"], 9000.0, "kinetic at end")
close(e["brakes_j"], 1234.5, "brakes")
close(e["fem_other_dissipation_j"], 1500.0 - 1234.5, "other FEM dissipation")
close(e["contact_dissipation_j"], 160.0, "contact dissipation from the first contact on")
close(e["dissipation_before_contact_j"], 40.0, "dissipation before the first contact")
close(e["block_potential_change_j"], 800.0, "potential energy from the step before contact to the end")
close(e["interface_mismatch_j"], -10.0, "mismatch")
assert e["guard_fired"] is False and e["created_max_j"] == 0.0
assert "output steps only" in out.stdout and os.path.getsize(os.path.join(tmp, "r.png")) > 0

# a block at rest at the first output step that reaches the net at 12 m/s (a rock released on
# a slope): the impact is its velocity at the first contact (0.002 s), from the output step
# before (6 m/s at 0.001 s) and the acceleration since the one before that (6000 m/s²); the
# braking time runs from the contact, not from the rest at t = 0
rest = os.path.join(tmp, "rest")
shutil.copytree(run, rest)
t2 = np.array([0.0, 0.001, 0.05, 0.1, 0.15])
va2 = np.array([0.0, 6.0, 6.0, -2.0, -3.0])
with h5py.File(os.path.join(rest, "dem.h5"), "w") as f:
    f["time"] = t2
    f["particles/body"] = np.array([0, 0], dtype=np.int32)
    f["particles/velocity"] = np.stack([np.outer(va2, d) + side, np.outer(va2, d) - side], axis=1)
out = subprocess.run([py, script, rest, "--json", os.path.join(tmp, "r3.json")], capture_output=True, text=True)
assert out.returncode == 0, (out.returncode, out.stderr)
r3 = json.load(open(os.path.join(tmp, "r3.json")))
close(r3["impact_speed_m_s"], 12.0, "impact speed of a block released at rest", 1e-9)
close(float(np.dot(r3["impact_direction"], d)), 1.0, "impact direction", 1e-12)
close(r3["block_stop_s"], 0.05 + 0.05 * 6.0 / 8.0, "stop time after the contact", 1e-9)
# a run in which the block never reaches the net: no figures, exit 2 saying so
with h5py.File(os.path.join(rest, "coupling.h5"), "a") as f:
    f["steps/in_contact"][...] = 0
out = subprocess.run([py, script, rest], capture_output=True, text=True)
assert out.returncode == 2 and "never touched the barrier" in out.stderr, (out.returncode, out.stderr)

# a folder without coupling.h5; a fem.json that is not a barrier
bad = os.path.join(tmp, "bad")
shutil.copytree(run, bad)
os.remove(os.path.join(bad, "coupling.h5"))
out = subprocess.run([py, script, bad], capture_output=True, text=True)
assert out.returncode == 2 and "coupling.h5: missing" in out.stderr, (out.returncode, out.stderr)
# a fem.h5 of an older fem_solver (no /element_sets): no overload figures, the rest as before
with h5py.File(os.path.join(bad, "fem.h5"), "a") as f:
    del f["element_sets"]
shutil.copy(os.path.join(run, "coupling.h5"), bad)
out = subprocess.run([py, script, bad, "--json", os.path.join(tmp, "r2.json")], capture_output=True, text=True)
assert out.returncode == 0 and "breaking loads" not in out.stdout, (out.returncode, out.stderr)
assert json.load(open(os.path.join(tmp, "r2.json")))["overload"] is None
os.remove(os.path.join(bad, "coupling.h5"))
json.dump({"nodes": [], "elements": [], "element_sets": [], "node_sets": {}},
          open(os.path.join(bad, "fem.json"), "w"))
out = subprocess.run([py, script, bad], capture_output=True, text=True)
assert out.returncode == 2 and "node_sets.net missing" in out.stderr, (out.returncode, out.stderr)
print("PASS")
