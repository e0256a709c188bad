#!/usr/bin/env bash
# End to end: coupler.json "interface_compliance" (coupler/README.md, "Interface Jacobian";
# protocol/README.md §3.4) on cases/steel_net as committed — steel wire-rope net (E 1e11 Pa),
# granite rock of 710 kg at 10 m/s, rock–net restitution 0.2, strong coupling at Δt 1e-3 s
# with the interface Jacobian and Aitken from the full step — over 0.15 s, against the same
# run without it (eq. (35) in both). With it the FEM also returns its compliance at the
# contact nodes, and the DEM solves each step against a net that yields instead of a rigid
# one: an impact step's first iterate is no longer MN-deep.
# Checks (measured over 0.15 s, with structure_predictor and compliance_proximity, their
# defaults: 3.95 against 2.10 iterations per contact step, at most 12 against 9; peak
# deflection of node 220 and the interface mismatch the same):
#  - both runs reliable, exit 0; the summary says the compliance was used and counts the
#    tries; coupling.h5 has the interface_compliance attribute (1, and 0 without it);
#  - at least one try went on without the compliance: at the impact (step 7, measured 1 of
#    150 tries) the DEM's search ends every contact while the structure's linearisation still
#    predicts force there, and the try goes on without it (coupler/cpl_loop.c, lost_contact), its
#    9 iterations within the largest count checked below;
#  - at least 15 % fewer iterations per contact step, and no larger largest count;
#  - the peak deflection of node 220 agrees within 0.5 %, the summed interface mismatch
#    within 0.1 % of the input energy, the structure's impulse within 0.5 % of the
#    particles';
#  - with interface_jacobian false the coupler warns that it has no effect, and run_case.sh
#    lists the warning before its verdict.
# And a contact onset at a large step: cases/rest_position (a 253 kg rock on a light cable) at
# rock–cable restitution 0.1 and 5× its Δt (0.05 s), 1.5 s. There the DEM's search starts
# where the rock does not reach the wall, and the full Newton step puts it millimetres deep.
# A search that only halved back cycled between the two; the search now brackets the onset
# and closes it (dem_solver/dem_compliance.c). Checked: reliable, exit 0, no step rejected,
# and no try went on without the compliance (with 12 evaluations per search, one did).
. tests/e2e_lib.sh
[ -d cases/steel_net ] || { echo "SKIP: cases/steel_net missing"; exit 77; }
common=(--set coupler.end_time=0.15 --set fem.analysis.end_time_s=0.15)
run_case plain cases/steel_net "${common[@]}"
run_case compliance cases/steel_net "${common[@]}" --set coupler.interface_compliance=true
expect_reliable plain compliance
grep -q "^coupler: interface compliance: the DEM solved with the structure's compliance; [0-9]* of [0-9]* tries" \
  "$NC_TMP/compliance/coupler.log" || fail "compliance: the summary does not say that it was used"
grep -Eq "^coupler: interface compliance: .*; [1-9][0-9]* of [0-9]+ tries went on without it" \
  "$NC_TMP/compliance/coupler.log" \
  || fail "compliance: no try went on without the compliance at the impact: $(grep "interface compliance:" "$NC_TMP/compliance/coupler.log")"
! grep -q "interface compliance" "$NC_TMP/plain/coupler.log" || fail "plain: compliance said used"
run_case jac_off cases/steel_net --set coupler.end_time=0.003 --set fem.analysis.end_time_s=0.003 \
  --set coupler.interface_compliance=true --set coupler.interface_jacobian=false
grep -q "^  coupler.json: interface_compliance has no effect: .*interface_jacobian is false" \
  "$NC_TMP/jac_off.out" || fail "jac_off: no warning that interface_compliance has no effect"
! grep -q "has no effect" "$NC_TMP/compliance.out" || fail "compliance: a warning on a valid set-up"

"$PY" - "$NC_TMP" <<'PY' || exit 1
import sys, h5py
sys.path.insert(0, "scripts")
import nc_results as R
tmp = sys.argv[1]
r = {}
for name in ("plain", "compliance"):
    d = "%s/%s" % (tmp, name)
    c = R.load_coupling(d)
    it = c.iterations[c.in_contact > 0]
    with h5py.File(d + "/coupling.h5", "r") as f:
        q = dict(on=float(f.attrs["interface_compliance"]),
                 impulse=float(f.attrs["impulse_missed_share"]),
                 mismatch=float(f["/energy/interface_created"][:].sum()),
                 e_in=float(f["/energy/input"][:].max()))
    q.update(avg=float(it.mean()), mx=int(it.max()),
             peak=float(abs(R.load_monitor(d).node(220)).max()))
    r[name] = q
    print("%-10s interface_compliance %g: %.2f iterations per contact step (at most %d), "
          "interface mismatch %.1f J of %.0f J, impulse missed %.3g, peak %.5f m"
          % (name, q["on"], q["avg"], q["mx"], q["mismatch"], q["e_in"], q["impulse"], q["peak"]))
p, c = r["plain"], r["compliance"]
assert p["on"] == 0.0 and c["on"] == 1.0, "coupling.h5 interface_compliance attribute"
assert c["avg"] <= 0.85 * p["avg"], "the compliance saved less than 15 %% of the iterations per " \
    "contact step (%.2f against %.2f)" % (c["avg"], p["avg"])
assert c["mx"] <= p["mx"], "a larger largest count with the compliance (%d against %d)" % (c["mx"], p["mx"])
assert abs(c["peak"] - p["peak"]) <= 0.005 * p["peak"], "peak deflections differ by more than 0.5 %"
assert abs(c["mismatch"] - p["mismatch"]) <= 0.001 * p["e_in"], "the compliance changed the interface mismatch"
assert abs(c["impulse"]) <= 0.005, "the structure's impulse %.3g from the particles'" % c["impulse"]
PY

[ -d cases/rest_position ] || { echo "SKIP: cases/rest_position missing"; exit 77; }
OPENBLAS_NUM_THREADS=1 run_case onset cases/rest_position --set coupler.interface_compliance=true \
  --set coupler.dt=0.05 --set fem.analysis.dt_s=0.05 --set coupler.end_time=1.5 \
  --set fem.analysis.end_time_s=1.5 --set dem.materials.0.restitution=0.1
grep -v '^$' "$NC_TMP/onset/coupler.log" | tail -n 1 | grep -q "^coupler: results are reliable" \
  || fail "onset: not reliable: $(tail -n 1 "$NC_TMP/onset/coupler.log")"
grep -Eq "^coupler: interface compliance: .*; 0 of [0-9]+ tries went on without it" \
  "$NC_TMP/onset/coupler.log" \
  || fail "onset: a try went on without the compliance: $(grep "interface compliance:" "$NC_TMP/onset/coupler.log")"
grep -q "^coupler: step control: no step rejected" "$NC_TMP/onset/coupler.log" \
  || fail "onset: tries rejected: $(grep "step control:" "$NC_TMP/onset/coupler.log")"

# A rock sliding through a net, its contacts changing within the step: cases/angled_net (a
# 97 kg rock through a net of 0.03 kg nodes) at restitution 0.1 and 5× its Δt with the
# compliance, its predictor, the proximity and newton_estimate, 0.2 s, one BLAS thread as
# scripts/study.py runs it: the study's last run out of its target. The DEM's searches there
# take up to 50 evaluations. With at most 12 a quarter stopped unsolved, their tries
# stalled, and the run took 3.9 iterations per contact step counting every try, 14 at most,
# with a rejected try (with 30: 2.67 and 11). Checked, counted as the study counts them
# (measured: 2.28 and 3 over 46 contact steps, with one BLAS thread and with two): reliable,
# no step rejected, no try without the compliance, at most 3 per contact step on average and
# 10 in a step; /iterations/compliance marks the iterations whose DEM solve was against the
# compliance (none in the run without it).
[ -d cases/angled_net ] || { echo "SKIP: cases/angled_net missing"; exit 77; }
OPENBLAS_NUM_THREADS=1 run_case sliding cases/angled_net --set coupler.interface_compliance=true \
  --set coupler.newton_estimate=0.1 --set coupler.work_tolerance=0 \
  --set coupler.dt=1e-3 --set fem.analysis.dt_s=1e-3 --set dem.materials.0.restitution=0.1 \
  --set dem.net_wall.restitution=0.1
expect_reliable sliding
grep -q "^coupler: step control: no step rejected" "$NC_TMP/sliding/coupler.log" \
  || fail "sliding: tries rejected: $(grep "step control:" "$NC_TMP/sliding/coupler.log")"
grep -Eq "^coupler: interface compliance: .*; 0 of [0-9]+ tries went on without it" \
  "$NC_TMP/sliding/coupler.log" \
  || fail "sliding: a try went on without the compliance: $(grep "interface compliance:" "$NC_TMP/sliding/coupler.log")"
"$PY" - "$NC_TMP" <<'PY' || exit 1
import sys, h5py, numpy as np
sys.path.insert(0, "scripts")
import study
tmp = sys.argv[1]
with h5py.File(tmp + "/plain/coupling.h5", "r") as f:
    assert not np.array(f["/iterations/compliance"]).any(), "plain: an iteration marked with the compliance"
with h5py.File(tmp + "/sliding/coupling.h5", "r") as f:
    comp = np.array(f["/iterations/compliance"]).ravel()
r = study.jacobian_metrics(tmp + "/sliding", 0.0, 220, 2)
print("sliding: %d contact steps, %.2f iterations per contact step counting every try, at most %d; "
      "%d of %d iterations with the compliance" % (r["contact_steps"], r["all_avg"], r["all_max"],
                                                   comp.sum(), len(comp)))
assert comp.any(), "sliding: no iteration marked with the compliance"
assert r["contact_steps"] >= 30, "sliding: %d contact steps (46 measured), the rock did not slide through" % r["contact_steps"]
assert study.meets_iterations(r), "sliding: %.2f per contact step, at most %d (target <= %g and <= %d)" \
    % (r["all_avg"], r["all_max"], study.TARGET_AVG, study.TARGET_MAX)
PY
echo "PASS: test_interface_compliance"
