#!/usr/bin/env bash
# Checkpoint/resume end to end with the Python participants (scripts/participants: the rigid
# plate on a spring as the FEM, the ball with a damped contact, ζ = 0.3, as the DEM), started
# by scripts/run_case.sh: a run stopped by SIGINT (exit 130) and one killed with its whole
# process group (SIGKILL) are continued with `run_case.sh --resume DIR`; coupling.h5 (every
# dataset but the wall-clock /timing/total), iterations.log, plate.csv and ball.csv must be
# identical to those of the uninterrupted run, bit for bit (tests/coupler/resume_lib.sh).
# Strong coupling with Aitken and, in the second run, IQN-ILS on the forces (columns kept
# across steps), 750 steps of 2 ms, a checkpoint every 0.1 s.
. tests/e2e_lib.sh
. tests/coupler/resume_lib.sh
set -m
case_dir=tests/coupler/cases/plate_ball
participants=(--fem-program "$PY scripts/participants/spring_plate.py"
              --dem-program "$PY scripts/participants/ball_dem.py")
files="coupling.h5 iterations.log plate.csv ball.csv"

resume_check py_int "$case_dir" int "$files" --quiet "${participants[@]}" \
  --set coupler.checkpoint.interval_s=0.1
resume_check py_kill "$case_dir" kill "$files" --quiet "${participants[@]}" \
  --set coupler.checkpoint.interval_s=0.1 --set coupler.relaxation.method=iqn-ils \
  --set coupler.relaxed_quantity=force

# the coupler keeps its two newest checkpoints, the participants theirs
n=$(ls "$NC_TMP/py_int.a/checkpoint" | grep -c '^coupler_step_.*\.h5$')
[ "$n" -eq 2 ] || fail "expected the 2 newest coupler checkpoints, found $n: $(ls "$NC_TMP/py_int.a/checkpoint")"

# --resume of a folder without a checkpoint: exit 2 naming the manifest
scripts/run_case.sh tests/coupler/cases/plate_ball --out "$NC_TMP/no_ckpt" --quiet \
  "${participants[@]}" --set coupler.end_time=0.02 > /dev/null 2>&1 || fail "short run failed"
out=$(scripts/run_case.sh --resume "$NC_TMP/no_ckpt" 2>&1); rc=$?
[ $rc -eq 2 ] || fail "--resume without checkpoint: exit $rc, expected 2: $out"
echo "$out" | grep -q "no complete checkpoint: .*no_ckpt/checkpoint/latest.json is missing" \
  || fail "--resume without checkpoint: unclear message: $out"
# a manifest naming a file that is not there
mkdir -p "$NC_TMP/no_ckpt/checkpoint"
printf '{"checkpoint": "step_000001", "step": 1, "files": {"coupler": "coupler_step_000001.h5", "fem": "fem_step_000001.json", "dem": "dem_step_000001.json"}}\n' \
  > "$NC_TMP/no_ckpt/checkpoint/latest.json"
out=$(scripts/run_case.sh --resume "$NC_TMP/no_ckpt" 2>&1); rc=$?
[ $rc -eq 2 ] && echo "$out" | grep -q "coupler_step_000001.h5" \
  || fail "--resume with an incomplete checkpoint: exit $rc: $out"
printf 'not json' > "$NC_TMP/no_ckpt/checkpoint/latest.json"
out=$(scripts/run_case.sh --resume "$NC_TMP/no_ckpt" 2>&1); rc=$?
[ $rc -eq 2 ] && echo "$out" | grep -q "not a checkpoint manifest" \
  || fail "--resume with a malformed manifest: exit $rc: $out"
# --resume with a case folder or --set is refused
out=$(scripts/run_case.sh "$case_dir" --resume "$NC_TMP/py_int.b" 2>&1); rc=$?
[ $rc -eq 2 ] || fail "--resume with CASE_DIR accepted: $out"
out=$(scripts/run_case.sh --resume "$NC_TMP/py_int.b" --set coupler.dt=1 2>&1); rc=$?
[ $rc -eq 2 ] || fail "--resume with --set accepted: $out"
# the coupler itself: a clear error naming the manifest
out=$("$NC_BIN/coupler" "$case_dir/coupler.json" --output "$NC_TMP/empty" --resume \
      --fem-endpoint tcp://127.0.0.1:1 --dem-endpoint tcp://127.0.0.1:1 2>&1); rc=$?
[ $rc -eq 1 ] && echo "$out" | grep -q "empty/checkpoint/latest.json: no checkpoint to resume from" \
  || fail "coupler --resume without checkpoint: exit $rc: $out"
echo "PASS"
