#!/usr/bin/env bash
# End to end: the structure's answer in the DEM's model of it (coupler/README.md
# "Interface Jacobian", `interface_compliance` and `structure_predictor`;
# docs/notes/interface_jacobian.md, item 8) on cases/terrain_net — a rock rolling down an STL
# slope into a standing net — at rock–net restitution 0.3 and 5× its Δt (0.005 s), with the
# interface Jacobian, Aitken from the full step, interface_compliance and newton_estimate 0.1,
# over 2.15 s. Three runs:
#  - eq. (35) without the compliance (the reference for the peak deflection);
#  - the compliance without the structure predictor: the coupler moves the interface nodes
#    the DEM does not touch by the structure's compliance rows (compliance_interface), so that
#    a contact step's first residual measures the DEM's model of the structure rather than
#    the net's answer to a force change that model held. Measured 2.78 iterations per contact
#    step, every try counted; 3.16 when the coupler moved only the nodes the DEM moved;
#  - with the structure predictor (the default): each try after a step with contact begins
#    with the structure's motion under the last step's force. Measured 2.26 per contact step,
#    at most 5 (eq. (35) without the compliance: 6.38, at most 18).
# Checks:
#  - all three reliable, exit 0; the summary counts the structure predictor's FEM solves in
#    the third run only; coupling.h5 says the predictor was on in the third run only
#    (structure_predictor and interface_compliance attributes);
#  - without the predictor at most 3.0 iterations per contact step, every try counted;
#  - with it at most 3 on average and 10 at most, every try counted, and at least 15 % fewer
#    per contact step than without it;
#  - the peak deflection of node 52 (along the slope) of both within 0.5 % of eq. (35)'s
#    (measured 0.05 %).
. tests/e2e_lib.sh
[ -d cases/terrain_net ] || { echo "SKIP: cases/terrain_net missing"; exit 77; }
common=("${TERRAIN_5X[@]}")
run_case paper cases/terrain_net "${common[@]}"
# compliance_proximity off in both: the test is of the predictor (the proximity has its own)
run_case rows cases/terrain_net "${common[@]}" --set coupler.newton_estimate=0.1 \
  --set coupler.interface_compliance=true --set coupler.structure_predictor=false \
  --set coupler.compliance_proximity=false
run_case predictor cases/terrain_net "${common[@]}" --set coupler.newton_estimate=0.1 \
  --set coupler.interface_compliance=true --set coupler.compliance_proximity=false
expect_reliable paper rows predictor
grep -Eq "^coupler: structure predictor: [1-9][0-9]* of the [0-9]+ FEM solves" \
  "$NC_TMP/predictor/coupler.log" || fail "predictor: the summary does not count its FEM solves"
! grep -q "structure predictor" "$NC_TMP/rows/coupler.log" || fail "rows: predictor said used"

"$PY" - "$NC_TMP" <<'PY' || exit 1
import sys
sys.path[:0] = ["scripts", "tests/coupler"]
from contact_steps import measure
r = measure(sys.argv[1], ("paper", "rows", "predictor"), 52, 0, "structure_predictor")
p, w, s = r["paper"], r["rows"], r["predictor"]
assert p["on"] == 0.0 and w["on"] == 0.0 and s["on"] == 1.0, "coupling.h5 structure_predictor attribute"
assert w["avg"] <= 3.0, "without the predictor %.2f iterations per contact step" % w["avg"]
assert s["avg"] <= 3.0 and s["mx"] <= 10, "with the predictor %.2f per contact step, at most %d" % (s["avg"], s["mx"])
assert s["avg"] <= 0.85 * w["avg"], "the predictor saved less than 15 %% (%.2f against %.2f)" % (s["avg"], w["avg"])
for name in ("rows", "predictor"):
    assert abs(r[name]["peak"] - p["peak"]) <= 0.005 * p["peak"], "%s: peak %.5f against %.5f" % (name, r[name]["peak"], p["peak"])
PY
echo "PASS: test_structure_predictor"
