#!/usr/bin/env bash
# End to end: coupler.json "newton_estimate" (coupler/README.md, "Interface Jacobian") on
# cases/steel_net as committed — steel wire-rope net (E 1e11 Pa), granite rock of 710 kg at
# 10 m/s, rock–net restitution 0.2, strong coupling at Δt 1e-3 s with the interface Jacobian
# and Aitken from the full step — over 0.15 s, against the same run with eq. (35) alone.
# With the Jacobian the structure's answer is Newton's iterate; after an iteration that cut
# the velocity residual to θ ≤ 0.1 of the one before, the error of that answer is estimated
# as θ/(1 − θ) times the residual, and the step is accepted when the estimate meets the
# tolerance instead of spending one more iteration to confirm it.
# Checks (measured over 0.15 s: 3.96 against 3.11 iterations per contact step, 89 of 154
# steps accepted on the estimate; peak deflection of node 220 the same to 0.02 %; interface
# mismatch the same to 0.005 % of the input energy; the structure's linearised impulse
# 0.046 % from the particles', against 0.0001 % with eq. (35)):
#  - both runs reliable, exit 0; the summary names the estimate and counts its steps, and
#    coupling.h5 has the newton_estimate and estimate_steps attributes (0 without it);
#  - the estimate saves at least 10 % of the iterations per contact step;
#  - the peak deflection of node 220 agrees within 0.5 %, the summed interface mismatch
#    within 0.1 % of the input energy;
#  - the impulse the structure solved with stays within 0.5 % of the particles' (the impulse
#    guard's own limit is 5 %);
#  - where it cannot act (interface_jacobian false, the weak scheme; work_tolerance with
#    relaxed_quantity "force") the coupler warns and run_case.sh lists the warning before its
#    verdict, also with --quiet; the committed set-up has no such warning.
. tests/e2e_lib.sh
[ -d cases/steel_net ] || { echo "SKIP: cases/steel_net missing"; exit 77; }
common=(--set coupler.end_time=0.15 --set fem.analysis.end_time_s=0.15)
run_case paper cases/steel_net "${common[@]}" --set coupler.newton_estimate=0
run_case estimate cases/steel_net "${common[@]}" --set coupler.newton_estimate=0.1
for r in paper estimate; do
  grep -v '^$' "$NC_TMP/$r/coupler.log" | tail -n 1 | grep -q "^coupler: results are reliable" \
    || fail "$r: not reliable: $(tail -n 1 "$NC_TMP/$r/coupler.log")"
done
# the options' warnings, on 3 steps each
short=(--set coupler.end_time=0.003 --set fem.analysis.end_time_s=0.003)
run_case jac_off cases/steel_net "${short[@]}" --set coupler.newton_estimate=0.1 \
  --set coupler.interface_jacobian=false
run_case weak cases/steel_net "${short[@]}" --set coupler.newton_estimate=0.1 --set coupler.scheme=weak
run_case force cases/steel_net "${short[@]}" --set coupler.work_tolerance=1e-6 \
  --set coupler.relaxed_quantity=force
expect_warning() {
  grep -q "^  coupler.json: $2 has no effect: .*$3" "$NC_TMP/$1.out" \
    || fail "$1: no warning that $2 has no effect ($3): $(grep warning "$NC_TMP/$1.out")"
}
expect_warning jac_off newton_estimate "interface_jacobian is false"
expect_warning weak newton_estimate "the weak scheme"
expect_warning force work_tolerance 'relaxed_quantity "force"'
! grep -q "has no effect" "$NC_TMP/estimate.out" || fail "estimate: a warning on the committed set-up"

grep -Eq "newton_estimate 0.1: [1-9][0-9]* of [0-9]+ steps by the latter" "$NC_TMP/estimate/coupler.log" \
  || fail "estimate: the summary does not name the Newton error estimate and count its steps"

"$PY" - "$NC_TMP" <<'PY' || exit 1
import sys, h5py, numpy as np
tmp = sys.argv[1]
r = {}
for name in ("paper", "estimate"):
    with h5py.File("%s/%s/coupling.h5" % (tmp, name), "r") as f:
        it = f["/steps/iterations"][:]
        contact = f["/steps/in_contact"][:] > 0
        r[name] = dict(avg=float(it[contact].mean()), mx=int(it[contact].max()),
                       mismatch=float(f["/energy/interface_created"][:].sum()),
                       e_in=float(f["/energy/input"][:].max()),
                       estimate=float(f.attrs["newton_estimate"]),
                       by_estimate=int(f.attrs["estimate_steps"]), steps=len(it),
                       impulse=float(f.attrs["impulse_missed_share"]))
    with h5py.File("%s/%s/fem.h5" % (tmp, name), "r") as f:
        ids = list(f["/monitor/node_ids"][:])
        r[name]["peak"] = float(np.abs(f["/monitor/displacement"][:, ids.index(220), 2]).max())
    q = r[name]
    print("%-9s newton_estimate %g: %.2f iterations per contact step (at most %d), %d of %d steps "
          "by the estimate, interface mismatch %.1f J of %.0f J, impulse missed %.3g, peak %.5f m"
          % (name, q["estimate"], q["avg"], q["mx"], q["by_estimate"], q["steps"], q["mismatch"],
             q["e_in"], q["impulse"], q["peak"]))
p, e = r["paper"], r["estimate"]
assert p["estimate"] == 0.0 and e["estimate"] == 0.1, "coupling.h5 newton_estimate attribute"
assert p["by_estimate"] == 0 and 0 < e["by_estimate"] <= e["steps"], "estimate_steps counted wrongly"
assert e["avg"] <= 0.9 * p["avg"], "the estimate saved less than 10 %% of the iterations per contact " \
    "step (%.2f against %.2f)" % (e["avg"], p["avg"])
assert abs(e["peak"] - p["peak"]) <= 0.005 * p["peak"], "peak deflections differ by more than 0.5 %"
assert abs(e["mismatch"] - p["mismatch"]) <= 0.001 * p["e_in"], "the estimate changed the interface mismatch"
assert e["impulse"] <= 0.005, "the structure's impulse is %.3g from the particles'" % e["impulse"]
print("PASS")
PY
