#!/usr/bin/env bash
# The coupler's checks that strong coupling can repeat a step, against the Python pair
# (scripts/participants, case tests/coupler/cases/plate_ball, 0.05 s):
#  1. a participant without the capability 'restore' is refused at start of a strong run,
#     with a message naming it and the way out (weak coupling), and runs weakly;
#  2. a participant that announces 'restore' but does not restore (spring_plate.py
#     --no-restore, plate under its own weight so its first solve moves it) is caught on
#     the first solve of the run (the solve sent twice gives different answers), and one
#     that restores passes the same check;
#  3. a retryable failure (spring_plate.py --retryable-above) makes the coupler retry the
#     step with a smaller dt; the run and the participant succeed.
set -u
: "${NC_BIN:?}" "${NC_TMP:?}"
PY=${PYTHON:-/usr/bin/python3}
case_dir=tests/coupler/cases/plate_ball
plate="$PY scripts/participants/spring_plate.py"
ball="$PY scripts/participants/ball_dem.py"
short=(--set coupler.end_time=0.05)
fail() { echo "FAIL: $*"; exit 1; }

run() {   # name fem-program [args...] -> run_case's exit status
  local name=$1 fem=$2; shift 2
  scripts/run_case.sh "$case_dir" --out "$NC_TMP/$name" --fem-program "$fem" \
    --dem-program "$ball" "${short[@]}" "$@" >"$NC_TMP/$name.out" 2>&1
}

# 1. no 'restore': refused before any step in a strong run, fine in a weak one
run no_capability "$plate --capabilities=" && fail "strong run accepted a participant without 'restore'"
log=$NC_TMP/no_capability/coupler.log
grep -q "fem (netcouple spring_plate.py) does not announce the capability 'restore'" "$log" \
  || fail "unclear message: $(cat "$log")"
grep -q 'use "scheme": "weak"' "$log" || fail "message does not say what to do: $(cat "$log")"
grep -q "t = " "$log" && fail "steps were run before the refusal: $(cat "$log")"
run no_capability_weak "$plate --capabilities=" --set coupler.scheme=weak \
  || fail "weak run refused: $(cat "$NC_TMP/no_capability_weak/coupler.log")"

# 2. a participant that does not restore is caught on its first solve
run no_restore "$plate --no-restore" --set fem.gravity=-9.81 && fail "non-restoring participant accepted"
log=$NC_TMP/no_restore/coupler.log
grep -q "fem: step 0 (t = 0 s), iteration 1, solve: does not restore its start-of-step state" "$log" \
  || fail "not caught or unclear: $(cat "$log")"
grep -q "verify_restore" "$log" || fail "message does not name the switch: $(cat "$log")"
run restores "$plate" --set fem.gravity=-9.81 \
  || fail "restoring participant refused: $(cat "$NC_TMP/restores/coupler.log")"
grep -q "protocol 2" "$NC_TMP/restores/coupler.log" || fail "not version 2"

# 3. retryable failures: 0.002 s fails, 0.001 s is taken, the run and the plate exit 0
run retryable "$plate --retryable-above 0.0015" \
  || fail "run with retryable failures failed: $(cat "$NC_TMP/retryable.out")"
log=$NC_TMP/retryable/coupler.log
grep -q "requested retryable failure" "$log" || fail "no retry seen: $(cat "$log")"
grep -q "retrying with dt = 0.001 s" "$log" || fail "not retried with half the step: $(cat "$log")"
grep -q "results are reliable" "$log" || fail "verdict: $(cat "$log")"
"$PY" - "$NC_TMP/retryable" <<'PY' || exit 1
import sys, h5py, numpy as np
with h5py.File(sys.argv[1] + "/coupling.h5", "r") as f:
    dt = f["/steps/dt"][:]
    t = f["/steps/time"][:]
# the retried steps were taken with 0.001 s, none above the participant's limit
assert dt.max() <= 0.0015 and abs(t[-1] - 0.05) < 1e-12, (dt.max(), t[-1])
print("retryable: %d steps, dt %g..%g s" % (len(dt), dt.min(), dt.max()))
PY
echo PASS
