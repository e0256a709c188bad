#!/usr/bin/env bash
# Paper 7.1/7.2 claim: "at dt = 1e-2 s weak coupling loses contact after the first
# impact (the contact force drops to zero and returns) while strong keeps it; weak at 1e-3
# does not lose it". cases/rest_position, COR 1 (the case's value), runs shortened to 0.8 s
# (the first impact lasts 0.25-0.7 s), compared with the independent fine-step reference
# scripts/analysis/reference_explicit.py (no coupling, dt 2e-5 s, about 2 s of CPU).
#
# What "keeps contact" means here. With COR 1 the undamped sphere chatters PHYSICALLY at the
# start and end of the impact: the reference has 11 contact windows before 0.75 s, the main
# one W = [0.376, 0.606] s (its longest). So no scheme can or should show a single contact
# window; the test uses W (computed from the reference, not hard-coded):
#  - strong 1e-2 keeps contact: non-zero contact force (coupling.h5 /steps/contact_force,
#    step average) in every coupling step overlapping W (contact-free time in W < 1e-6 s;
#    measured 0: its window [0.34, 0.67] covers W) and its peak u_A is within 5 % of the
#    reference's (measured -0.5351 vs -0.5511 m, 2.9 %).
#  - weak 1e-2 loses contact and regains it with a jump: contact-free time in W > 25 % of W
#    (measured 57 %: 1-2 steps on, 1-2 off, longest contact 30 ms = 13 % of W) and the force on
#    return > 3x the reference's maximum (measured 148 kN vs 20.9 kN, 7x).
#  - weak 1e-3 does not lose contact in the paper's sense, i.e. it follows the reference's
#    contact pattern: contact-free time in W < 25 % of W (measured 12 %: the reference's own
#    chatter right after W, shifted by a few ms), longest contact >= 50 % of W (measured 71 %),
#    max force within 50 % of the reference's (measured +26 %), peak u_A within 1 % of the
#    reference's (measured -0.5512 vs -0.5511 m). It does NOT have one continuous contact over
#    W (7 short gaps of 1-8 ms); neither has the reference around W's ends.
#  - both weak runs create energy, so the coupler's energy guard fires (they opt in with
#    accept_energy_growth, the warning is checked): weak 1e-3's total mechanical energy rises
#    up to 52 J (2.4 % of the 2.2 kJ input) above its start during the impact, although the
#    cable is damped and the contact is elastic; strong 1e-2 stays below the guard's limit.
# Tolerances are the midpoints between the measured values of the "keeps" and "loses" runs
# (a factor >= 2 away from each measurement).
# These are claims about the paper's plain exchange, so every run here sets
# "interface_jacobian": false. All of this is for COR 1 (the case's value). With a damped contact (COR <= 0.5) weak coupling
# is unstable even at 1e-3 s (docs/notes/damped_contact.md), as the paper reports for small COR (7.4).
. tests/e2e_lib.sh
case_dir=cases/rest_position
[ -d "$case_dir" ] || { echo "SKIP: $case_dir missing"; exit 77; }
T=0.8

"$PY" scripts/analysis/reference_explicit.py $T 2e-5 1.0 --save "$NC_TMP/ref.npz" \
  > "$NC_TMP/ref.log" 2>&1 || { tail "$NC_TMP/ref.log"; fail "reference_explicit.py failed"; }

run() {   # name scheme dt [run_case.sh arguments]
  local name=$1 scheme=$2 dt=$3
  shift 3
  run_case "$name" "$case_dir" --set coupler.scheme=$scheme --set coupler.dt=$dt \
    --set fem.analysis.dt_s=$dt --set coupler.end_time=$T --set fem.analysis.end_time_s=$T \
    --set dem.materials.0.restitution=1.0 --set coupler.interface_jacobian=false "$@"
}
# weak 1e-2 loses contact and creates energy: the energy guard fires (opted in, checked)
run weak_dt1e-2 weak 1e-2 --set coupler.accept_energy_growth=true
grep -q "^warning: step [0-9]* (t = .* s): the run has created .* J of energy" \
  "$NC_TMP/weak_dt1e-2/coupler.log" || fail "weak_dt1e-2: no energy-created warning"
run weak_dt1e-3 weak 1e-3 --set coupler.accept_energy_growth=true
grep -q "^warning: step [0-9]* (t = .* s): the run has created .* J of energy" \
  "$NC_TMP/weak_dt1e-3/coupler.log" || fail "weak_dt1e-3: no energy-created warning"
run strong_dt1e-2 strong 1e-2

"$PY" - "$NC_TMP" <<'PY' || exit 1
import sys
import numpy as np
sys.path.insert(0, "scripts")
import nc_results as R
tmp = sys.argv[1]
UNTIL = 0.75    # end of the first impact window (docs/notes/damped_contact.md)
ref = R.reference_contact(tmp + "/ref.npz", UNTIL)
ref_iv, W, L, ref_fmax, ref_peak = ref["intervals"], ref["main"], ref["length"], ref["fmax"], ref["peak"]
print("reference: %d contact windows before %.2f s, main window W = [%.3f, %.3f] s, max |F| %.0f N, "
      "peak u_A %.4f m" % (len(ref_iv), UNTIL, W[0], W[1], ref_fmax, ref_peak))
assert 0.1 < L < 0.5, "reference main contact window implausible: %s" % (W,)

res = {}
for name in ("weak_dt1e-2", "weak_dt1e-3", "strong_dt1e-2"):
    r = R.run_contact(tmp + "/" + name, UNTIL, W)
    res[name] = r
    print("%-14s %2d windows, contact-free in W %.4f s (%3.0f %%), longest %.3f s (%3.0f %% of W), "
          "max |F| %7.0f N (%.2fx ref), peak u_A %.4f m"
          % (name, r["n"], r["free"], 100 * r["free"] / L, r["longest"], 100 * r["longest"] / L, r["fmax"],
             r["fmax"] / ref_fmax, r["peak"]))

s, w2, w3 = res["strong_dt1e-2"], res["weak_dt1e-2"], res["weak_dt1e-3"]
assert s["free"] < 1e-6, "strong 1e-2 lost contact inside the reference's main window"
assert abs(s["peak"] / ref_peak - 1) < 0.05, "strong 1e-2 peak u_A not within 5 % of the reference"
assert w2["free"] > 0.25 * L, "weak 1e-2 did not lose contact inside the main window"
assert w2["lost"], "weak 1e-2: contact force never dropped to zero and returned"
assert w2["fmax"] > 3 * ref_fmax, "weak 1e-2 regained contact without a force jump"
assert w3["free"] < 0.25 * L, "weak 1e-3 lost contact inside the main window"
assert w3["longest"] >= 0.5 * L, "weak 1e-3 has no sustained contact"
assert abs(w3["fmax"] - ref_fmax) < 0.5 * ref_fmax, "weak 1e-3 contact force far from the reference"
assert abs(w3["peak"] - ref_peak) < 0.01 * abs(ref_peak), "weak 1e-3 peak u_A not within 1 % of the reference"
PY
echo PASS
