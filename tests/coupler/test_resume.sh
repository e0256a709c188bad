#!/usr/bin/env bash
# Checkpoint/resume end to end with the real solvers: the small net case
# (tests/coupler/cases/small_net: 7 x 7 cable net, one rock, COR 0.5, strong coupling with
# Aitken, 0.4 s) with a checkpoint every 0.05 s. A run stopped by SIGINT to
# run_case.sh (exit 130) and one killed with its whole process group (SIGKILL), and one with
# the structure's compliance in the DEM (interface_compliance) stopped by SIGINT, are continued
# with `run_case.sh --resume DIR`; every dataset of fem.h5, dem.h5 and coupling.h5 (except
# the wall-clock ones, tests/coupler/resume_lib.sh) must be identical to the uninterrupted
# run's, with the same shapes; also for a net that starts at rest in its static equilibrium
# under its own weight (the FEM's interface then starts where that equilibrium holds it),
# whose resume with another start state is refused.
# Skipped (exit 77) while fem_solver or dem_solver does not announce the capability
# 'checkpoint' (the coupler then says "checkpoints off" at start-up, naming it).
. tests/e2e_lib.sh
. tests/coupler/resume_lib.sh
set -m
case_dir=tests/coupler/cases/small_net
args=(--set coupler.checkpoint.interval_s=0.05)

# can both solvers checkpoint? (the coupler's start-up warning names the one that cannot)
scripts/run_case.sh "$case_dir" --out "$NC_TMP/probe" --quiet --set coupler.end_time=0.002 \
  --set coupler.checkpoint.interval_s=0.001 > "$NC_TMP/probe.out" 2>&1 \
  || { tail -n 20 "$NC_TMP/probe.out"; fail "probe run failed"; }
if grep -q "checkpoints off" "$NC_TMP/probe/coupler.log"; then
  echo "SKIP: $(grep -m 1 -o "checkpoints off: .*" "$NC_TMP/probe/coupler.log")"
  exit 77
fi

resume_check net_int "$case_dir" int "coupling.h5 fem.h5 dem.h5 iterations.log" --quiet "${args[@]}"
resume_check net_kill "$case_dir" kill "coupling.h5 fem.h5 dem.h5 iterations.log" --quiet "${args[@]}"
# with the structure's compliance in the DEM (coupler.json interface_compliance): a resumed
# step starts from the compliance of the last FEM solve, which the checkpoint holds
resume_check net_compliance "$case_dir" int "coupling.h5 fem.h5 dem.h5 iterations.log" --quiet \
  "${args[@]}" --set coupler.interface_compliance=true
# a net that starts at rest in its static equilibrium under its own weight (fem.json
# analysis.initial_state): the resumed FEM finds the same start and interface again
resume_check net_settled "$case_dir" int "coupling.h5 fem.h5 dem.h5 iterations.log" --quiet \
  "${args[@]}" --set fem.self_weight=true --set fem.analysis.initial_state=static
# resumed with another start (initial_state changed in the run's fem.json): the FEM refuses
# the checkpoint, naming the cause, instead of continuing from a start 0.0076 m elsewhere
cp -r "$NC_TMP/net_settled.b" "$NC_TMP/net_moved"
"$PY" - "$NC_TMP/net_moved/fem.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
d["analysis"]["initial_state"] = "reference"
json.dump(d, open(sys.argv[1], "w"))
PY
if scripts/run_case.sh --resume "$NC_TMP/net_moved" > "$NC_TMP/net_moved.out" 2>&1; then
  fail "net_moved: a resume from another start state was accepted"
fi
grep -q "the checkpoint was written by a run that started from another state" "$NC_TMP/net_moved/fem.log" \
  || { tail -n 5 "$NC_TMP/net_moved/fem.log" "$NC_TMP/net_moved.out"; fail "net_moved: the FEM did not name the changed start"; }
echo "PASS"
