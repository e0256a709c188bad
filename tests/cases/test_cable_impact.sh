#!/usr/bin/env bash
# Paper 7.1, cases/cable_impact: "weak coupling works at a small step; at 1e-2 s the
# weak scheme jumps (contact lost and regained), the strong scheme keeps contact". Runs shortened
# to 1.2 s (first impact and the main contact 0.25-0.92 s), compared with the independent
# fine-step reference scripts/analysis/reference_explicit.py (--case cable_impact --swap: the
# case's moduli, no coupling, dt 2e-5 s). W = the reference's longest contact window (measured
# [0.509, 0.918] s), computed here, not hard-coded.
#  - weak 2e-4 works: contact-free time in W < 2 % of W (measured 0.3 %), same number of contact
#    windows as the reference up to 1 s (measured 7 and 7), peak u_A within 1 % (measured
#    -1.6453 vs -1.6448 m), max contact force within 10 % (measured +0.6 %). The paper finds
#    weak working at 1e-3; here it does not (README "Impact on a compliant cable": the contact
#    of the 5.4 t sphere on a 1.3 kg node, omega ~ 1500 rad/s, limits the weak step to a few
#    1e-4 s), so the test uses the largest step measured to work.
#  - strong 1e-2 keeps contact: contact-free time in W < 5 % of W (measured 0.2 %) and peak u_A
#    within 2 % (measured -0.70 %).
#  - weak 1e-2 jumps: contact-free time in W > 25 % of W (measured 64 %), contact lost and
#    regained, and a force on return > 2x the reference's maximum (measured 3.35x); it creates
#    energy, so the coupler's energy guard fires, and the structure misses part of the
#    sphere's impulse, so the impulse guard fires too (the run opts in with
#    accept_energy_growth and accept_impulse_loss, and both verdicts are checked); weak 2e-4
#    passes the impulse guard.
. tests/e2e_lib.sh
case_dir=cases/cable_impact
[ -d "$case_dir" ] || { echo "SKIP: $case_dir missing"; exit 77; }
T=1.2

"$PY" scripts/analysis/reference_explicit.py $T 2e-5 1.0 --case cable_impact --swap x \
  --save "$NC_TMP/ref.npz" > "$NC_TMP/ref.log" 2>&1 || { tail "$NC_TMP/ref.log"; fail "reference_explicit.py failed"; }

run() {   # name scheme dt [run_case.sh arguments]
  local name=$1 scheme=$2 dt=$3
  shift 3
  run_case "$name" "$case_dir" --set coupler.scheme=$scheme --set coupler.dt=$dt \
    --set coupler.end_time=$T "$@"
}
run weak_dt2e-4 weak 2e-4
run weak_dt1e-2 weak 1e-2 --set coupler.accept_energy_growth=true \
  --set coupler.accept_impulse_loss=true
grep -q "NOT reliable: the force the structure solved with carried" "$NC_TMP/weak_dt1e-2/coupler.log" \
  || fail "weak_dt1e-2: no impulse verdict"
grep -q "NOT reliable: the force the structure solved with" "$NC_TMP/weak_dt2e-4/coupler.log" \
  && fail "weak_dt2e-4: impulse verdict"
run strong_dt1e-2 strong 1e-2
grep -q "^warning: step [0-9]* (t = .* s): the run has created .* J of energy" \
  "$NC_TMP/weak_dt1e-2/coupler.log" || fail "weak_dt1e-2: no energy-created warning"

"$PY" - "$NC_TMP" <<'PY' || exit 1
import sys
import numpy as np
sys.path.insert(0, "scripts")
import nc_results as R
tmp = sys.argv[1]
UNTIL = 1.0
ref = R.reference_contact(tmp + "/ref.npz", UNTIL)
ref_iv, W, L, ref_fmax, ref_peak = ref["intervals"], ref["main"], ref["length"], ref["fmax"], ref["peak"]
print("reference: %d contact windows before %.2f s, main window W = [%.3f, %.3f] s, max |F| %.0f N, "
      "peak u_A %.4f m" % (len(ref_iv), UNTIL, W[0], W[1], ref_fmax, ref_peak))
assert 0.2 < L < 0.6, "reference main contact window implausible: %s" % (W,)

res = {}
for name in ("weak_dt2e-4", "weak_dt1e-2", "strong_dt1e-2"):
    r = R.run_contact(tmp + "/" + name, UNTIL, W)
    res[name] = r
    print("%-14s %2d windows, contact-free in W %.4f s (%4.1f %%), max |F| %8.0f N (%.3fx ref), "
          "peak u_A %.4f m (%+.2f %%)" % (name, r["n"], r["free"], 100 * r["free"] / L, r["fmax"],
                                         r["fmax"] / ref_fmax, r["peak"], 100 * (r["peak"] / ref_peak - 1)))

w, s, j = res["weak_dt2e-4"], res["strong_dt1e-2"], res["weak_dt1e-2"]
assert w["free"] < 0.02 * L, "weak 2e-4 lost contact inside the reference's main window"
assert w["n"] == len(ref_iv), "weak 2e-4: %d contact windows, reference %d" % (w["n"], len(ref_iv))
assert abs(w["peak"] / ref_peak - 1) < 0.01, "weak 2e-4 peak u_A not within 1 % of the reference"
assert abs(w["fmax"] / ref_fmax - 1) < 0.10, "weak 2e-4 max contact force not within 10 % of the reference"
assert s["free"] < 0.05 * L, "strong 1e-2 lost contact inside the reference's main window"
assert abs(s["peak"] / ref_peak - 1) < 0.02, "strong 1e-2 peak u_A not within 2 % of the reference"
assert j["free"] > 0.25 * L, "weak 1e-2 did not lose contact inside the main window"
assert j["lost"], "weak 1e-2: contact force never dropped to zero and returned"
assert j["fmax"] > 2 * ref_fmax, "weak 1e-2 regained contact without a force jump"
PY
echo PASS
