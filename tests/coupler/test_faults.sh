#!/usr/bin/env bash
# Fault behaviour of the coupler, with the Python participants:
#  1. the DEM is killed with SIGKILL mid-run -> coupler exits non-zero naming dem, the step
#     and the iteration; the FEM is told to shut down and exits 0; coupling.h5 stays readable.
#  2. the FEM replies an error (Newton-failure stand-in) -> message with its reason, step and
#     iteration; the DEM exits 0 after SHUTDOWN, the failed FEM exits non-zero.
#  3. SIGINT to the coupler -> exit 130, both participants shut down, files readable.
#  4. a participant that stops answering (SIGSTOP) -> reply timeout naming it.
set -u
: "${NC_BIN:?}" "${NC_TMP:?}"
PY=${PYTHON:-/usr/bin/python3}
P=scripts/participants
case_dir=tests/coupler/cases/plate_ball
pids=()
cleanup() { for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null; done; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$dir"/*.log; do echo "--- $f"; cat "$f"; done; exit 1; }

start() {   # dir [extra fem args]
  dir=$1; shift
  rm -rf "$dir"; mkdir -p "$dir"
  cp "$case_dir"/*.json "$dir"/
  # long run, so there is time to interfere
  "$PY" - "$dir/coupler.json" <<'PYSET'
import json, sys
c = json.load(open(sys.argv[1])); c["end_time"] = 60.0
c["timeouts"] = {"connect": 20, "reply": 3, "shutdown": 2}
json.dump(c, open(sys.argv[1], "w"))
PYSET
  "$PY" $P/spring_plate.py "$dir/fem.json" --endpoint 'tcp://127.0.0.1:*' --output "$dir" \
    --endpoint-file "$dir/fem.endpoint" --idle-timeout 30 "$@" >"$dir/fem.log" 2>&1 &
  fem_pid=$!; pids+=($fem_pid)
  "$PY" $P/ball_dem.py "$dir/dem.json" --endpoint 'tcp://127.0.0.1:*' --output "$dir" \
    --endpoint-file "$dir/dem.endpoint" --idle-timeout 30 >"$dir/dem.log" 2>&1 &
  dem_pid=$!; pids+=($dem_pid)
  for i in $(seq 200); do [ -s "$dir/fem.endpoint" ] && [ -s "$dir/dem.endpoint" ] && break; sleep 0.05; done
  "$NC_BIN/coupler" "$dir/coupler.json" --output "$dir" --fem-endpoint "$(cat "$dir/fem.endpoint")" \
    --dem-endpoint "$(cat "$dir/dem.endpoint")" >"$dir/coupler.log" 2>&1 &
  cpl_pid=$!; pids+=($cpl_pid)
}

wait_steps() {   # n: until iterations.log has n rows
  for i in $(seq 400); do
    [ -f "$dir/iterations.log" ] && [ "$(grep -vc '^#' "$dir/iterations.log")" -ge "$1" ] && return 0
    sleep 0.05
  done
  fail "the run did not reach $1 steps"
}

wait_pid() {   # pid seconds -> exit status (fails when still running)
  for i in $(seq $(( $2 * 20 ))); do kill -0 "$1" 2>/dev/null || break; sleep 0.05; done
  kill -0 "$1" 2>/dev/null && fail "process $1 still running after $2 s"
  wait "$1"
}

h5_ok() {
  "$PY" -c "
import h5py, sys
with h5py.File('$dir/coupling.h5', 'r') as f:
    n = f['/steps/time'].shape[0]
    assert n > 0 and f['/steps/contact_force'].shape == (n, 3), n
print('coupling.h5 readable,', n, 'steps')" || fail "coupling.h5 not readable"
}

# 1. SIGKILL of the DEM
start "$NC_TMP/kill"
wait_steps 20
kill -KILL "$dem_pid"
wait_pid "$cpl_pid" 15; rc=$?
[ $rc -ne 0 ] || fail "coupler exit 0 after the DEM died"
# (the kill may land in a solve, which has an iteration, or in begin/accept, which has none)
grep -Eq "error: dem: step [0-9]+ \(t = [^)]*\), (iteration [0-9]+, solve|begin_step|accept_step): .*(closed the connection|did not answer)" \
  "$dir/coupler.log" || fail "message does not name dem/step/iteration/reason"
wait_pid "$fem_pid" 10 || fail "fem did not exit 0 after SHUTDOWN"
h5_ok
echo "1 ok: $(grep error "$dir/coupler.log")"

# 2. error reply of the FEM at step 50 (in contact), iteration 2
start "$NC_TMP/error" --fail-at 50:2
wait_pid "$cpl_pid" 15; rc=$?
[ $rc -eq 1 ] || fail "coupler exit $rc, expected 1"
grep -q "fem: step 50 (t = .*), iteration 2, solve: .*requested failure at step 50" "$dir/coupler.log" \
  || fail "error reply not reported with step/iteration/reason"
wait_pid "$dem_pid" 10 || fail "dem did not exit 0 after SHUTDOWN"
wait_pid "$fem_pid" 10 && fail "failed fem exited 0"
h5_ok
echo "2 ok: $(grep error "$dir/coupler.log")"

# 3. Ctrl-C
start "$NC_TMP/sigint"
wait_steps 20
kill -INT "$cpl_pid"
wait_pid "$cpl_pid" 15; rc=$?
[ $rc -eq 130 ] || fail "coupler exit $rc after SIGINT, expected 130"
grep -q "interrupted" "$dir/coupler.log" || fail "no 'interrupted' message"
wait_pid "$fem_pid" 10 || fail "fem did not exit 0"
wait_pid "$dem_pid" 10 || fail "dem did not exit 0"
h5_ok
echo "3 ok"

# 4. a participant that stops answering (reply timeout 3 s)
start "$NC_TMP/hang"
wait_steps 20
kill -STOP "$dem_pid"
wait_pid "$cpl_pid" 20; rc=$?
kill -CONT "$dem_pid"
[ $rc -eq 1 ] || fail "coupler exit $rc after a hang, expected 1"
grep -q "error: dem: step .*did not answer within 3.0 s" "$dir/coupler.log" || fail "timeout not reported"
wait_pid "$fem_pid" 10 || fail "fem did not exit 0"
h5_ok
echo "4 ok"
echo PASS
