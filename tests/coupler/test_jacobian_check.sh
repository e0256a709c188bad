#!/usr/bin/env bash
# End to end: coupler.json "jacobian_check" (coupler/README.md, coupler/cpl_jacobian_check.h)
# with the real programs on cases/rest_position at restitution 0.3 (the rock lands at 0.25 s;
# its impact steps go through contact backtracking), 0.6 s, the default strong settings.
# Checks:
#  - with the check on every step, the summary counts the checks (2 extra DEM solves each)
#    and none above 1e-3, and the largest recorded miss is below 1e-4: dem_solver's K is the
#    derivative of its own step (measured: 1.1e-6 to 0.6 s, 1.4e-6 over 1.5 s,
#    docs/notes/interface_jacobian.md);
#  - /iterations/jacobian_miss holds one finite value per check, NaN elsewhere, and is NaN
#    throughout with the check off (no summary line then);
#  - the check changes nothing in the run: every iteration's residual and contact force, the
#    structure's monitor displacements and the rock's positions are the same bit for bit
#    (the DEM's probe solves restore its start-of-step state like any repeated solve).
. tests/e2e_lib.sh
common=(--set coupler.end_time=0.6 --set fem.analysis.end_time_s=0.6
        --set dem.materials.0.restitution=0.3)
run_case plain cases/rest_position "${common[@]}"
run_case checked cases/rest_position "${common[@]}" --set coupler.jacobian_check=1
! grep -q "jacobian check" "$NC_TMP/plain/coupler.log" \
  || fail "plain: a jacobian check line although the check is off"
line=$(grep "coupler: jacobian check:" "$NC_TMP/checked/coupler.log") \
  || fail "checked: no jacobian check line in the summary"
echo "$line"
echo "$line" | grep -Eq "check: [1-9][0-9]* linearisations .*\(([0-9]+) extra DEM solves\): relative miss above 0.001 in 0," \
  || fail "checked: the summary line does not count checks without a miss above 1e-3"
checks=$(echo "$line" | sed -E 's/.*check: ([0-9]+) linearisations.*/\1/')
"$PY" - "$NC_TMP/plain" "$NC_TMP/checked" "$checks" <<'PY' || exit 1
import sys, h5py, numpy as np
plain, checked, checks = sys.argv[1], sys.argv[2], int(sys.argv[3])
with h5py.File(plain + "/coupling.h5", "r") as a, h5py.File(checked + "/coupling.h5", "r") as b:
    assert np.isnan(a["/iterations/jacobian_miss"][()]).all(), "plain: a jacobian_miss recorded"
    miss = b["/iterations/jacobian_miss"][()]
    found = miss[~np.isnan(miss)]
    print("checked: %d misses recorded, largest %.3g" % (found.size, found.max()))
    assert found.size == checks, "%d misses recorded, the summary says %d" % (found.size, checks)
    assert found.max() < 1e-4, "a miss of %.3g: K is not the derivative of the DEM's step" % found.max()
    for name in ("/iterations/residual", "/iterations/contact_force", "/steps/time",
                 "/steps/iterations"):
        assert np.array_equal(a[name][()], b[name][()]), "%s differs with the check" % name
with h5py.File(plain + "/fem.h5", "r") as a, h5py.File(checked + "/fem.h5", "r") as b:
    assert np.array_equal(a["/monitor/displacement"][()], b["/monitor/displacement"][()]), \
        "the structure moved differently with the check"
with h5py.File(plain + "/dem.h5", "r") as a, h5py.File(checked + "/dem.h5", "r") as b:
    assert np.array_equal(a["/particles/position"][()], b["/particles/position"][()]), \
        "the rock moved differently with the check"
print("PASS")
PY
