#!/usr/bin/env bash
# End to end: the structure's compliance also at the nodes a rock in contact may reach in the
# next step (coupler/README.md "Interface Jacobian", `compliance_proximity`;
# docs/notes/interface_jacobian.md, item 9) on cases/terrain_curtain — a rock rolling down an
# STL slope through a hanging curtain into a net — at rock–net restitution 0.3 and 5× its Δt
# (0.005 s), with the interface Jacobian, Aitken from the full step, interface_compliance,
# structure_predictor and newton_estimate 0.1, over 2.15 s. Three runs:
#  - eq. (35) without the compliance (the reference for the peak deflection);
#  - compliance_proximity false: the compliance covers the nodes of the DEM's last Jacobian
#    only, and where the rock reaches new nodes the DEM holds them where the coupler put
#    them (measured 2.43 iterations per contact step, at most 6; 2.51 and 12 when the DEM's
#    search took at most 12 evaluations);
#  - compliance_proximity true (the default): the DEM names the nodes the rock may reach by
#    zero Jacobian blocks, the FEM's compliance covers them (measured 2.04, at most 4; eq. (35)
#    without the compliance: 7.69, at most 24).
# Checks:
#  - all three reliable, exit 0; coupling.h5 says compliance_proximity was on in the third
#    run only;
#  - with it at most 3 iterations per contact step on average and 10 at most, every try
#    counted, and at least 10 % fewer per contact step than without it;
#  - the peak deflection of node 52 (along the slope) of both within 0.5 % of eq. (35)'s;
#  - no note on the dashpot in the DEM's log (the case's Hunt–Crossley dashpot is continuous
#    at the first touch; test_contact_ends.sh has eq. (A.5)'s).
. tests/e2e_lib.sh
[ -d cases/terrain_curtain ] || { echo "SKIP: cases/terrain_curtain missing"; exit 77; }
common=("${TERRAIN_5X[@]}")
compliance=(--set coupler.newton_estimate=0.1 --set coupler.interface_compliance=true)
run_case paper cases/terrain_curtain "${common[@]}"
run_case held cases/terrain_curtain "${common[@]}" "${compliance[@]}" \
  --set coupler.compliance_proximity=false
run_case proximity cases/terrain_curtain "${common[@]}" "${compliance[@]}"
expect_reliable paper held proximity
! grep -q "^dem_solver: note: .*dashpot" "$NC_TMP/proximity/dem.log" \
  || fail "proximity: the DEM noted a dashpot the case does not have"

"$PY" - "$NC_TMP" <<'PY' || exit 1
import sys
sys.path[:0] = ["scripts", "tests/coupler"]
from contact_steps import measure
r = measure(sys.argv[1], ("paper", "held", "proximity"), 52, 0, "compliance_proximity")
p, h, x = r["paper"], r["held"], r["proximity"]
assert p["on"] == 0.0 and h["on"] == 0.0 and x["on"] == 1.0, "coupling.h5 compliance_proximity attribute"
assert x["avg"] <= 3.0 and x["mx"] <= 10, "with proximity %.2f per contact step, at most %d" % (x["avg"], x["mx"])
assert x["avg"] <= 0.9 * h["avg"], "proximity saved less than 10 %% (%.2f against %.2f)" % (x["avg"], h["avg"])
for name in ("held", "proximity"):
    assert abs(r[name]["peak"] - p["peak"]) <= 0.005 * p["peak"], "%s: peak %.5f against %.5f" % (name, r[name]["peak"], p["peak"])
PY
echo "PASS: test_compliance_proximity"
