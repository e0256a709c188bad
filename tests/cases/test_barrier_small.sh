#!/usr/bin/env bash
# A coupled barrier impact: the certification block (scripts/make_ead_block.py, concrete E 3e10
# Pa, COR 0.25, friction 0.5; 416.7 kg at 12 m/s = 30 kJ, along the net normal) strikes the
# net centre of a one-module barrier (scripts/make_barrier.py --modules 1: posts 3 m, spacing
# 5 m, wire-rope net of 8 mm ropes at 0.5 m meshes, support and upslope ropes with brakes,
# ropes E 1e11 Pa, make_barrier's damping: Rayleigh tau 2 1/s, kappa 1e-4 s, Bossak -0.1, and
# its start at rest in static equilibrium), strong coupling at dt 2.5e-4 s with the interface
# Jacobian and Aitken from the full step, at most 30 iterations, step rejection down to
# dt/512, 0.17 s (the block stops at about 0.15 s). The inputs are generated into $NC_TMP;
# nothing generated is committed. Settings that make it hold:
#  - max_iterations 30 and dt_min dt/512: with 10 iterations most contact steps end
#    unconverged; with 20 and dt/64 a few still do (7 of 3917, the contact force changing
#    between 44 and 284 kN from one iteration to the next at dt_min), one of them with a
#    409 J spike of contact energy that fires the energy guard;
#  - DEM sub-step 2e-6 s: with the automatic 1.3e-5 s the coupler's reduced steps (down to
#    3.9e-6 s) are shorter than one DEM sub-step and a net node moving into the block is
#    found deep inside it, a one-step spike of contact elastic energy (1.4 kJ) fires the
#    energy guard;
#  - 32 spheres (radius L/4, spacing 1.0 r) for the block's surface: 416 spheres cost 10x.
# Checks (tolerances inline):
#  - exit 0: every strong step converged and the energy guard stayed silent: the created
#    energy (coupling.h5 /energy/created) never above 1 % of the input energy + 1e-9 J;
#  - the block's kinetic energy just before contact is 1/2 m v^2 within 1 %; the interface
#    work balances: the DEM's and the FEM's work at the interface differ by < 2 % of the
#    impact energy (measured 44 J of 30 kJ); the energy no mechanism of the model accounts
#    for (the FEM integrator's dissipation and that mismatch) is < 2 % of it (measured 0.36 %;
#    0.9 % with Bossak -0.3 and no kappa, make_barrier's former defaults);
#  - the block is stopped: its velocity along the impact direction falls to <= 0 within the
#    run (it rebounds), and it rebounds with less energy than it came with: the block's
#    kinetic energy at the end < 0.75 of the impact energy;
#  - the brakes activated and dissipated energy: barrier_report's brake energy > 1 kJ and
#    equal to sum(F_a s + k_h s^2 / 2) over the brakes' strokes in fem.h5 (relative 1e-6);
#  - barrier_report.py's net_centre elongation equals the monitor's largest displacement along
#    the impact direction (1e-9 m) and lies between 0.3 and 3 m; residual height in (0, 1];
#  - no shackle passed its neighbour: at every output step no segment of a sliding rope is
#    shorter than 0.9 of make_barrier's 5 cm shackle gap. At 30 kJ the contact does not close
#    (shortest segment 0.23 m of 0.5 m); it does in the MEL test (docs/notes/shackle_contact.md)
#    and in tests/fem_solver/test_element_sliding.c;
#  - report.py's rope strain leaves out the sliding ropes (per segment) and the brakes
#    (stroke), names them, equals the largest strain of fem.h5's rope sets (printed to 6
#    digits: 1e-5 relative) and is a steel rope's (< 5 %, overloaded as the net ropes are).
. tests/e2e_lib.sh
case=$NC_TMP/case
mkdir -p "$case"
"$PY" scripts/make_barrier.py --modules 1 --spacing 5 --height 3 --mesh-size 0.5 \
  --end-time 0.17 --output "$case/fem.json" > "$NC_TMP/barrier.md" \
  || fail "make_barrier.py failed"
"$PY" - "$case" <<'PY' || fail "case generation failed"
import json, subprocess, sys
import numpy as np
case = sys.argv[1]
fem = json.load(open(case + "/fem.json"))
centre = np.array(fem["nodes"][fem["node_sets"]["net_centre"][0]])
tilt = np.radians(10.0)                          # make_barrier's default post tilt
n = np.array([0.0, np.cos(tilt), -np.sin(tilt)])  # net normal, downslope
# centre of mass 0.386 m before the net: half the block (L/2 = 0.33 m) plus ~5 cm clearance
pos = centre - 0.386 * n
subprocess.run(["/usr/bin/python3", "scripts/make_ead_block.py", "--energy-kj", "30", "--speed", "12",
                "--restitution", "0.25", "--sphere-radius", "0.25", "--spacing", "1.0",
                "--position"] + ["%.6f" % x for x in pos] + ["--direction"] + ["%.9f" % x for x in n]
               + ["--output", case + "/dem.json"], check=True, capture_output=True)
dem = json.load(open(case + "/dem.json"))
dem["net_wall"] = {"youngs_modulus_pa": 1e11, "poisson_ratio": 0.3, "friction": 0.5,
                   "restitution": 0.25, "cable_radius_m": 0.004}
dem["gravity"] = [0, 0, -9.81]
dem["dt_s"] = 2e-6
dem["output_interval_s"] = 0.005
json.dump(dem, open(case + "/dem.json", "w"), indent=1)
json.dump({"comment": "one-module barrier struck by a 30 kJ certification block",
           "scheme": "strong", "dt": 2.5e-4, "end_time": 0.17, "tolerance": 1e-6,
           "max_iterations": 30, "step_control": {"dt_min": 4.8828125e-07},
           "relaxation": {"method": "aitken", "alpha": 1.0, "first_iteration_cap": 1.0},
           "relaxed_quantity": "displacement_velocity"},
          open(case + "/coupler.json", "w"), indent=1)
PY
run_case run "$case"
"$PY" scripts/barrier_report.py "$NC_TMP/run" --json "$NC_TMP/report.json" --plot "$NC_TMP/report.png" \
  || fail "barrier_report.py failed"
"$PY" - "$NC_TMP/run" "$NC_TMP/report.json" <<'PY' || exit 1
import json, sys
import h5py
import numpy as np
run, rep = sys.argv[1], json.load(open(sys.argv[2]))
dem = json.load(open(run + "/dem.json"))
fem = json.load(open(run + "/fem.json"))
with h5py.File(run + "/coupling.h5", "r") as c:
    conv = c["steps/converged"][()]
    created, limit = c["energy/created"][()], c["energy/limit"][()]
    assert conv.all(), "%d steps unconverged" % int((conv == 0).sum())
    assert (created <= limit).all(), "energy created: %.4g J > limit" % created.max()
    print("steps %d, created at most %.4g J (limit %.4g J)" % (len(conv), created.max(), limit[-1]))
cl = dem["clusters"][0]
e_in = 0.5 * cl["mass_kg"] * float(np.dot(cl["velocity"], cl["velocity"]))
e = rep["energy"]
print("impact energy %.1f J, block kinetic at contact %.1f J, at the end %.1f J, interface "
      "mismatch %.1f J" % (e_in, e["block_kinetic_at_contact_j"], e["block_kinetic_end_j"],
                           e["interface_mismatch_j"]))
# the balance closes: the work the DEM's forces did on the net and the work the FEM received
# agree to 2 % of the impact energy (a step converged only loosely at the contact nodes loses
# energy there: 5.9 kJ of 30 kJ with the interface residual's velocity part left out)
assert abs(e["interface_mismatch_j"]) < 0.02 * e_in, "the interface work does not balance"
# and the rest of the balance: what no mechanism of the model (brakes, Rayleigh damping,
# contact dashpots, strain and kinetic energy) accounts for -- the FEM integrator's
# dissipation and the interface mismatch -- stays below 2 % of the impact energy (measured 0.36 %)
print("not attributed to a mechanism: %.1f J (integrator %.1f J)"
      % (e["unattributed_j"], e["fem_numerical_dissipation_j"]))
assert 0.0 <= e["fem_numerical_dissipation_j"] and abs(e["unattributed_j"]) < 0.02 * e_in, \
    "the energy balance does not close to 2 %"
assert abs(e["block_kinetic_at_contact_j"] - e_in) < 0.01 * e_in, "impact energy"
assert rep["block_stop_s"] is not None, "the block was not stopped"
assert e["block_kinetic_end_j"] < 0.75 * e_in, "the block rebounds with too much energy"
print("braking time %.4g s, max elongation net_centre %.3f m, residual height %.3f"
      % (rep["braking_time_s"], rep["max_centre_elongation_m"], rep["residual_height_ratio"]))
# brake energy, independently from the strokes
with h5py.File(run + "/fem.h5", "r") as f:
    stroke = f["output/element_stroke"][-1]
    eset = f["mesh/element_set"][()]
    mon = list(f["monitor/node_ids"][()])
    mu = f["monitor/displacement"][:, mon.index(fem["node_sets"]["net_centre"][0]), :]
    x = f["output/position"][()]
w = 0.0
for i, s in enumerate(fem["element_sets"]):
    if s["type"] == "brake":
        F_a, k_h = s["activation_force_n"], s["hardening_stiffness_n_per_m"]
        sp = stroke[eset == i]
        w += float((F_a * sp + 0.5 * k_h * sp ** 2).sum())
print("brakes %.1f J (from the strokes %.1f J)" % (e["brakes_j"], w))
assert e["brakes_j"] > 1e3, "the brakes did not work"
assert abs(e["brakes_j"] - w) <= 1e-6 * w, "brake energy disagrees with the strokes"
d = np.array(rep["impact_direction"])
assert abs(rep["max_centre_elongation_m"] - (mu @ d).max()) < 1e-9
assert 0.3 < rep["max_centre_elongation_m"] < 3.0, "unexpected elongation"
assert 0.0 < rep["residual_height_ratio"] <= 1.0, "residual height"
# shackle contact: consecutive nodes of every sliding rope stay at least 0.9 gap apart
for i, s in enumerate(fem["element_sets"]):
    if s["type"] != "sliding_cable":
        continue
    conn = np.array([e["nodes"] for e in fem["elements"] if e["set"] == s["name"]])
    seg = np.linalg.norm(x[:, conn[:, 1]] - x[:, conn[:, 0]], axis=2)
    print("%s: shortest segment %.4f m (gap %g m, %.4f m at rest)"
          % (s["name"], seg.min(), s["shackle_gap_m"], seg[0].min()))
    assert seg.min() >= 0.9 * s["shackle_gap_m"], "%s: shackles came closer than the gap" % s["name"]
PY
# report.py's rope strain is the ropes' (cable sets), not a sliding rope's per-segment stretch
# (which reads up to 146 % on a barrier) or a brake's stroke: a steel rope's few per cent (2.4 %
# here, the net ropes at 1.8 times their breaking load: the model has no rope failure), the
# sets left out named
"$PY" scripts/report.py "$NC_TMP/run" > "$NC_TMP/report.out" 2>&1 || fail "report.py failed"
"$PY" - "$NC_TMP/run" "$NC_TMP/report.out" <<'PY' || exit 1
import json, sys
import h5py
import numpy as np
run, out = sys.argv[1], open(sys.argv[2]).read()
line = [l for l in out.splitlines() if l.startswith("rope strain:")][0]
words = line.replace(",", "").split()
strain, element = float(words[3]), int(words[5])
print(line)
# independently: the largest strain of fem.h5 over the elements of the sets that are ropes
types = [s.get("type", "cable") for s in json.load(open(run + "/fem.json"))["element_sets"]]
with h5py.File(run + "/fem.h5", "r") as f:
    st, eset = f["output/strain"][()], f["mesh/element_set"][()]
ropes = np.isin(eset, [i for i, t in enumerate(types) if t not in ("sliding_cable", "brake", "post")])
expected = st[:, ropes].max()
print("largest strain of the rope sets in fem.h5: %.6g (of all elements: %.6g)" % (expected, st.max()))
assert abs(strain - expected) <= 1e-5 * expected, "report.py %g, fem.h5's rope sets %g" % (strain, expected)
assert ropes[element], "element %d is not a rope's" % element
assert 0.0 < strain < 0.05, "rope strain %g: not a steel rope's" % strain
md = open(run + "/report.md").read()
assert "(sliding_cable)" in md and "(brake)" in md, "the sets left out are not named"
PY
echo "PASS"
