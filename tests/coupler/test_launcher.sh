#!/usr/bin/env bash
# scripts/run_case.sh under faults (the Python participants on plate_ball, a long run so
# there is time to interfere):
#  1. the coupler is killed (SIGKILL) mid-run -> run_case.sh exits 1 within a few seconds,
#     names only the coupler as failed, the solvers as stopped, no program left running;
#  2. the coupler stops (SIGSTOP) -> its heartbeat goes stale; with --stall-limit 2 it is
#     stopped as stalled within the limit + grace, named alone as failed;
#  3. a DEM that dies before the handshake -> noticed within a few seconds (not after the
#     coupler's 20 s connect timeout), named as failed;
#  4. SIGINT to the whole job (as Ctrl-C on a terminal) and SIGTERM to run_case.sh alone ->
#     "stopped by user", exit 130, no program left running, coupling.h5 readable;
#  5. --help prints the usage and nothing else;
#  6. the FEM replies an error (a Newton failure stand-in) -> the FEM alone is named as failed
#     (the coupler's error names it), the coupler and the DEM as stopped;
#  8. run_case.sh itself killed (SIGKILL) while it waits for the endpoints, before the
#     coupler connects -> the programs already started do not outlive it (no orphan waiting
#     for a coupler until its idle timeout): gone within a few seconds;
#  9. a coupler.json the coupler refuses -> run_case.sh's check of the inputs stops with exit 2
#     before starting anything; started by hand with the solvers (a DEM slow to start), the
#     coupler tells them to go (both exit 0, not left to their idle timeout);
# 10. a case folder given as a symbolic link, and one that is read-only -> the output folder is
#     a folder of its own (writable for a user other than root) and --set changes its copies,
#     not the case's files;
# 11. a solver that publishes its endpoint after NC_ENDPOINT_WAIT_S -> failed, named, when it
#     wrote nothing meanwhile; waited for when it reports its progress;
#  7. on a terminal (a pseudo-terminal from script(1)) the coupler's live status line is shown
#     (time, remaining time, contact, deflection) with its messages, the final status line
#     stays, and coupler.log still holds everything without terminal control characters.
set -u
exec </dev/null   # script(1) below would read the test runner's list of tests from stdin
: "${NC_BIN:?}" "${NC_TMP:?}"
PY=${PYTHON:-/usr/bin/python3}
[ -x "$NC_BIN/coupler" ] || { echo "SKIP: $NC_BIN/coupler not built"; exit 77; }
case_dir=tests/coupler/cases/plate_ball
fem="$PY scripts/participants/spring_plate.py"
dem="$PY scripts/participants/ball_dem.py"
set -m   # each run_case.sh in its own process group, SIGINT not ignored (as from a terminal)
rpid=""
cleanup() { [ -n "$rpid" ] && kill -KILL -- "-$rpid" 2>/dev/null; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; cat "$out.out" 2>/dev/null; for f in "$out"/{coupler,fem,dem}.log; do echo "--- $f"; tail -n 20 "$f"; done; exit 1; }

launch() {   # name [run_case.sh arguments]: starts a 60 s run in the background
  out=$NC_TMP/$1; shift
  rm -rf "$out"
  scripts/run_case.sh "$case_dir" --out "$out" --quiet --set coupler.end_time=60 \
    --fem-program "$fem" --dem-program "$dem" "$@" > "$out.out" 2>&1 &
  rpid=$!
  start_s=$EPOCHREALTIME
}
child() {   # program name -> pid of that child of run_case.sh
  ps -o pid= -o args= --ppid "$rpid" | awk -v p="$1" '$0 ~ p {print $1; exit}'
}
wait_steps() {   # n: until iterations.log has n rows
  for _ in $(seq 300); do
    [ -f "$out/iterations.log" ] && [ "$(grep -vc '^#' "$out/iterations.log")" -ge "$1" ] && return 0
    kill -0 "$rpid" 2>/dev/null || fail "run_case.sh ended before $1 steps"
    sleep 0.05
  done
  fail "the run did not reach $1 steps"
}
finish() {   # seconds: waits for run_case.sh; sets rc and took (s, one decimal)
  local t0=$1
  for _ in $(seq $(( $2 * 20 ))); do kill -0 "$rpid" 2>/dev/null || break; sleep 0.05; done
  kill -0 "$rpid" 2>/dev/null && fail "run_case.sh still running after $2 s"
  wait "$rpid"; rc=$?
  took=$("$PY" -c "import sys; print('%.1f' % (float(sys.argv[2]) - float(sys.argv[1])))" "$t0" "$EPOCHREALTIME")
}
group_members() {   # pid and command of every process in run_case.sh's process group
  # (ps -g selects sessions, not process groups: filter on the pgid column)
  ps -eo pid=,pgid=,args= | awk -v g="$rpid" '$2 == g {$2 = ""; print}'
}
no_leftovers() {   # no process of the run may survive run_case.sh, nor its pipe's name
  local left
  left=$(group_members)
  [ -z "$left" ] || fail "processes left after run_case.sh: $left"
  [ ! -e "$out/coupler.alive" ] || fail "run_case.sh left $out/coupler.alive behind"
  rpid=""
}
h5_ok() {
  "$PY" -c "
import h5py
with h5py.File('$out/coupling.h5', 'r') as f:
    assert f['/steps/time'].shape[0] > 0" || fail "coupling.h5 not readable"
}
failed_line() { grep "^run_case: failed:" "$out.out"; }

# 1. a dead coupler
launch dead
wait_steps 20
cpl=$(child "bin/coupler"); [ -n "$cpl" ] || fail "no coupler process found"
t0=$EPOCHREALTIME; kill -KILL "$cpl"
finish "$t0" 10
[ "$rc" -eq 1 ] || fail "dead coupler: exit $rc, expected 1"
failed_line | grep -q "^run_case: failed: coupler (exit 137 = SIGKILL, .*; stopped: fem (.*), dem (.*)$" \
  || fail "dead coupler: '$(failed_line)'"
awk "BEGIN {exit !($took < 5)}" || fail "dead coupler: cleaned up after $took s (limit 5 s)"
no_leftovers
echo "1 ok ($took s): $(failed_line)"

# 2. a stalled coupler
launch stalled --stall-limit 2
wait_steps 20
cpl=$(child "bin/coupler")
t0=$EPOCHREALTIME; kill -STOP "$cpl"
finish "$t0" 15
[ "$rc" -eq 1 ] || fail "stalled coupler: exit $rc, expected 1"
failed_line | grep -q "^run_case: failed: coupler (stalled: no heartbeat (coupler.progress) for [0-9]* s, limit 2 s, .*; stopped: fem (.*), dem (.*)$" \
  || fail "stalled coupler: '$(failed_line)'"
# limit 2 s (+ up to 0.2 s of polling) + grace 3 s, and a margin for a loaded machine
awk "BEGIN {exit !($took >= 2 && $took < 7)}" || fail "stalled coupler: stopped after $took s (expected 2..7 s)"
no_leftovers
echo "2 ok ($took s): $(failed_line)"

# 3. a DEM that dies before the handshake
launch early_death --dem-program tests/coupler/participants/dies_after_endpoint.sh
t0=$start_s
finish "$t0" 15
[ "$rc" -eq 1 ] || fail "early death: exit $rc, expected 1"
failed_line | grep -Eq "^run_case: failed: dem \(exit 1 (while the coupler was connecting|before the handshake), .*; stopped: fem \(.*\)(, coupler \(.*\))?$" \
  || fail "early death: '$(failed_line)'"
grep -q "exiting before the handshake" "$out.out" || fail "early death: the DEM's last lines are not shown"
awk "BEGIN {exit !($took < 8)}" || fail "early death: noticed after $took s (limit 8 s)"
no_leftovers
echo "3 ok ($took s): $(failed_line)"

# 4. the user stops the job: SIGINT to all of it, SIGTERM to run_case.sh alone
for sig in INT TERM; do
  launch "user_$sig"
  wait_steps 20
  t0=$EPOCHREALTIME
  if [ $sig = INT ]; then kill -INT -- "-$rpid"; else kill -TERM "$rpid"; fi
  finish "$t0" 15
  [ "$rc" -eq 130 ] || fail "SIG$sig: exit $rc, expected 130"
  grep -q "^run_case: stopped by user (SIG$sig)" "$out.out" || fail "SIG$sig: no 'stopped by user'"
  grep -q "failed" "$out.out" && fail "SIG$sig: a program is reported as failed"
  awk "BEGIN {exit !($took < 8)}" || fail "SIG$sig: stopped after $took s (limit 8 s)"
  no_leftovers
  h5_ok
  echo "4 ok, SIG$sig ($took s): $(grep '^run_case:' "$out.out")"
done

# 5. --help: the usage, nothing of the script's source
out=$NC_TMP/help
scripts/run_case.sh --help > "$out.out" 2>&1 || fail "--help: exit status $?"
head -n 1 "$out.out" | grep -q "^usage: scripts/run_case.sh CASE_DIR" || fail "--help: first line"
grep -q "^Exit status:" "$out.out" || fail "--help: no exit status paragraph"
grep -Eq '^(set |root=|bin=|die\(\)|#|  *-h\|--help\)|EOF)' "$out.out" && fail "--help prints source lines"
[ "$(wc -l < "$out.out")" -lt 40 ] || fail "--help: $(wc -l < "$out.out") lines"
echo "5 ok"

# 6. an error reply of the FEM at step 50, iteration 2
launch error_reply --fem-program "$fem --fail-at 50:2"
finish "$start_s" 20
[ "$rc" -eq 1 ] || fail "error reply: exit $rc, expected 1"
failed_line | grep -q "^run_case: failed: fem (named by the coupler's error, see .*; stopped: dem (exit 0), coupler (exit 1)$" \
  || fail "error reply: '$(failed_line)'"
grep -q "coupler: error: fem: step 50 .*requested failure at step 50" "$out.out" || fail "error reply: the coupler's error is not shown"
no_leftovers
echo "6 ok: $(failed_line)"

# 8. run_case.sh killed before the coupler connects: its programs must not outlive it
launch orphans --dem-program tests/coupler/participants/never_publishes.sh
for _ in $(seq 200); do [ -s "$out/fem.endpoint" ] && break; sleep 0.05; done
[ -s "$out/fem.endpoint" ] || fail "orphans: the FEM published no endpoint"
kill -KILL "$rpid"
wait "$rpid" 2>/dev/null
t0=$EPOCHREALTIME
left="x"
for _ in $(seq 100); do
  left=$(group_members)
  [ -z "$left" ] && break
  sleep 0.05
done
[ -z "$left" ] || fail "orphans: left running 5 s after run_case.sh was killed: $left"
took=$("$PY" -c "import sys; print('%.1f' % (float(sys.argv[2]) - float(sys.argv[1])))" "$t0" "$EPOCHREALTIME")
rpid=""
echo "8 ok: the solvers ended $took s after run_case.sh was killed"

# 9. a coupler.json the coupler refuses. run_case.sh checks the three inputs first (--check):
# exit 2, the key named, nothing started. The coupler started by hand with the solvers (as
# run_case.sh did before the check, or a user's own launcher) reads their endpoint files all
# the same and tells them to go (both exit 0, not left to their idle timeout), the DEM taking
# 4 s to publish its endpoint
launch bad_config --set coupler.dt=-1 --dem-program tests/coupler/participants/slow_start.sh
t0=$start_s
finish "$t0" 10
[ "$rc" -eq 2 ] || fail "bad coupler.json: exit $rc, expected 2"
grep -q "^run_case: coupler: its input is not valid, nothing was started:" "$out.out" \
  && grep -q "coupler.json: dt: " "$out.out" || fail "bad coupler.json: the check's message"
[ ! -e "$out/fem.log" ] && [ ! -e "$out/coupler.log" ] || fail "bad coupler.json: a program was started"
rpid=""
echo "9 ok ($took s): run_case.sh: $(grep 'coupler.json: dt: ' "$out.out")"
by_hand=$NC_TMP/bad_config_by_hand
mkdir -p "$by_hand"
cp "$case_dir"/*.json "$by_hand"/
"$PY" - "$by_hand/coupler.json" <<'PY'
import json, sys
c = json.load(open(sys.argv[1])); c["dt"] = -1; json.dump(c, open(sys.argv[1], "w"))
PY
t0=$EPOCHREALTIME
(cd "$by_hand" && exec "$PY" "$OLDPWD/scripts/participants/spring_plate.py" fem.json --endpoint 'tcp://127.0.0.1:*' --output . \
   --endpoint-file fem.endpoint > fem.log 2>&1) & fem_pid=$!
(cd "$by_hand" && exec "$OLDPWD/tests/coupler/participants/slow_start.sh" dem.json \
   --endpoint 'tcp://127.0.0.1:*' --output . --endpoint-file dem.endpoint > dem.log 2>&1) & dem_pid=$!
(cd "$by_hand" && "$NC_BIN/coupler" coupler.json --output . --fem-endpoint-file fem.endpoint \
   --dem-endpoint-file dem.endpoint > coupler.log 2>&1); cpl_rc=$?
wait "$fem_pid"; fem_rc=$?
wait "$dem_pid"; dem_rc=$?
took=$("$PY" -c "import sys; print('%.1f' % (float(sys.argv[2]) - float(sys.argv[1])))" "$t0" "$EPOCHREALTIME")
[ "$cpl_rc" -eq 1 ] && grep -q "coupler.json: dt: " "$by_hand/coupler.log" \
  || fail "bad coupler.json by hand: coupler exit $cpl_rc: $(cat "$by_hand/coupler.log")"
[ "$fem_rc" -eq 0 ] && [ "$dem_rc" -eq 0 ] || fail "bad coupler.json by hand: fem exit $fem_rc, dem exit $dem_rc"
awk "BEGIN {exit !($took < 12)}" || fail "bad coupler.json by hand: the solvers ended after $took s (limit 12 s)"
echo "9 ok ($took s): by hand, the coupler exits 1 and the solvers 0"

# 11. a solver slow to publish its endpoint (4 s, NC_ENDPOINT_WAIT_S 2): one that says nothing
# meanwhile has failed, named with the limit; one that writes progress to its log is still
# starting and the run goes on (a large barrier's initial equilibrium takes minutes)
export NC_ENDPOINT_WAIT_S=2
launch silent_start --set coupler.end_time=0.2 --dem-program tests/coupler/participants/slow_start.sh
finish "$start_s" 15
[ "$rc" -eq 1 ] || fail "silent slow start: exit $rc, expected 1"
failed_line | grep -q "^run_case: failed: dem (did not publish its endpoint, and wrote nothing to dem.log, in 2 s (NC_ENDPOINT_WAIT_S)" \
  || fail "silent slow start: '$(failed_line)'"
no_leftovers
echo "11 ok ($took s): $(failed_line)"
launch talking_start --set coupler.end_time=0.2 \
  --dem-program tests/coupler/participants/slow_talking_start.sh
finish "$start_s" 30
[ "$rc" -eq 0 ] || fail "slow start with progress: exit $rc, expected 0"
# it was waited for past the limit, because it said it was still starting
grep -q "still starting (4 s)" "$out/dem.log" || fail "slow start with progress: dem.log: $(cat "$out/dem.log")"
grep -q "^coupler: results are reliable" "$out/coupler.log" || fail "slow start with progress: no verdict"
awk "BEGIN {exit !($took >= 4)}" || fail "slow start with progress: finished after $took s, before the DEM could start"
no_leftovers
unset NC_ENDPOINT_WAIT_S
echo "11 ok ($took s): a solver that reports its progress is waited for"

# 10. a case folder given as a symbolic link, and a read-only one
case_sum=$(cksum < cases/rest_position/coupler.json)
ln -s "$PWD/cases/rest_position" "$NC_TMP/linked_case"
mkdir -p "$NC_TMP/read_only"
cp -R cases/rest_position "$NC_TMP/read_only/case"
chmod 555 "$NC_TMP/read_only/case"
for c in "$NC_TMP/linked_case" "$NC_TMP/read_only/case"; do
  out=$NC_TMP/copy_of_${c##*/}
  rm -rf "$out"
  scripts/run_case.sh "$c" --out "$out" --quiet --set coupler.end_time=0.01 \
    --set fem.analysis.end_time_s=0.01 > "$out.out" 2>&1 || fail "10: the run of $c failed"
  [ -d "$out" ] && [ ! -L "$out" ] || fail "10: $out is not a folder of its own"
  # (root writes into a folder of mode 555: the mode matters, and is made writable, for others)
  [ "$(id -u)" -eq 0 ] || [ -w "$out" ] || fail "10: $out is not writable ($(stat -c %a "$out"))"
  "$PY" -c 'import json, sys; assert json.load(open(sys.argv[1]))["end_time"] == 0.01' \
    "$out/coupler.json" || fail "10: --set did not reach $out/coupler.json"
done
chmod 755 "$NC_TMP/read_only/case"
[ "$(cksum < cases/rest_position/coupler.json)" = "$case_sum" ] || fail "10: the case's coupler.json was changed"
echo "10 ok: a linked and a read-only case folder copied into writable folders, the case untouched"

# 7. the live status line on a terminal
if command -v script >/dev/null; then
  out=$NC_TMP/tty
  rm -rf "$out"
  script -qec "scripts/run_case.sh $case_dir --out $out --set coupler.end_time=1 \
    --fem-program '$fem' --dem-program '$dem'" /dev/null > "$out.out" 2>&1 \
    || fail "terminal run: exit status $?"
  tr '\r' '\n' < "$out.out" | sed 's/\x1b\[K//g' > "$out.lines"
  [ "$(grep -c "^t = [0-9.e-]* s ([0-9.]*%), [0-9:-]* left | contact [0-9]* | deflection [0-9.e-]* m (max [0-9.e-]* m)" "$out.lines")" -ge 2 ] \
    || fail "terminal run: fewer than 2 live status lines"
  grep -q $'\r\033\[K' "$out.out" || fail "terminal run: the status line is not rewritten in place"
  grep -q "^t = 1 s (100.0%), 00:00 left" "$out.lines" || fail "terminal run: no final status line"
  grep -q "^coupler: results are reliable" "$out.lines" || fail "terminal run: the coupler's messages are not shown"
  grep -q "^run_case: done" "$out.lines" || fail "terminal run: no verdict"
  grep -q "^t = 1 s (100.0%)" "$out/coupler.log" || fail "terminal run: coupler.log lacks the status lines"
  grep -q $'\r' "$out/coupler.log" && fail "terminal run: terminal control characters in coupler.log"
  echo "7 ok"
else
  echo "7 skipped: script(1) not installed"
fi
echo PASS
