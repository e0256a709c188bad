#!/usr/bin/env bash
# run_case.sh — run one coupled case: fem_solver + dem_solver + coupler on localhost.
#
#   scripts/run_case.sh CASE_DIR [--out DIR] [--set FILE.KEY=VALUE ...]
#                       [--fem-program CMD] [--dem-program CMD] [--quiet]
#
# CASE_DIR holds fem.json, dem.json, coupler.json and whatever they refer to (meshes, STL).
# Everything is copied into DIR (default: runs/<case>-<date-time>), --set overrides are
# applied to the copies, and all results land there: fem.h5, dem.h5, coupling.h5, their XDMF
# files, iterations.log and one log per process (fem.log, dem.log, coupler.log).
#   --set coupler.scheme=weak  --set coupler.relaxation.method=aitken
#   --set dem.materials.0.restitution=0.2   (numbers index lists; VALUE is JSON if it parses
#                                            as JSON, otherwise a string)
# The solvers bind free ports (tcp://127.0.0.1:*) and publish them in DIR/*.endpoint, so
# parallel runs never collide. Programs come from $NC_BIN if set, else <repo>/bin.
# --fem-program/--dem-program replace a solver by another participant command taking the same
# arguments (e.g. "/usr/bin/python3 scripts/participants/spring_plate.py").
# Exit status: 0 when all three programs succeeded; 3 (the coupler's) when the run finished
# but accepted unconverged steps or created energy (results NOT reliable; 0 with coupler.json
# "accept_unconverged" / "accept_energy_growth": true, still reported as not reliable);
# otherwise non-zero with a
# message naming the ones that failed. Ctrl-C stops the coupler cleanly (it shuts the
# solvers down).
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${NC_BIN:-$root/bin}
python=/usr/bin/python3
# The three processes take turns on the same cores: OpenMP threads that spin while waiting
# (the default) steal the CPU from the process that is working (100x slower runs).
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}

die() { echo "run_case: $*" >&2; exit 2; }

case_dir=""; out=""; sets=(); quiet=0
fem_program="$bin/fem_solver"; dem_program="$bin/dem_solver"
while [ $# -gt 0 ]; do
  case "$1" in
    --out) [ $# -ge 2 ] || die "--out needs a folder"; out=$2; shift 2 ;;
    --set) [ $# -ge 2 ] || die "--set needs FILE.KEY=VALUE"; sets+=("$2"); shift 2 ;;
    --fem-program) [ $# -ge 2 ] || die "--fem-program needs a command"; fem_program=$2; shift 2 ;;
    --dem-program) [ $# -ge 2 ] || die "--dem-program needs a command"; dem_program=$2; shift 2 ;;
    --quiet) quiet=1; shift ;;
    -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
    -*) die "unknown option $1 (see --help)" ;;
    *) [ -z "$case_dir" ] || die "only one CASE_DIR, got '$case_dir' and '$1'"; case_dir=$1; shift ;;
  esac
done
[ -n "$case_dir" ] || die "usage: run_case.sh CASE_DIR [--out DIR] [--set FILE.KEY=VALUE ...]"
[ -d "$case_dir" ] || die "$case_dir: no such case folder"
for f in fem.json dem.json coupler.json; do
  [ -f "$case_dir/$f" ] || die "$case_dir/$f: missing (a case folder holds fem.json, dem.json, coupler.json)"
done
[ -x "$bin/coupler" ] || die "$bin/coupler not found (build with make, or set NC_BIN)"
bin=$(cd "$bin" && pwd)
[ "$fem_program" = "$root/bin/fem_solver" ] && fem_program="$bin/fem_solver"
[ "$dem_program" = "$root/bin/dem_solver" ] && dem_program="$bin/dem_solver"
[ -n "$out" ] || out="runs/$(basename "$(cd "$case_dir" && pwd)")-$(date +%Y%m%d-%H%M%S)"
mkdir -p "$out" || die "$out: cannot create the output folder"
out=$(cd "$out" && pwd)
case_abs=$(cd "$case_dir" && pwd)
if [ "$case_abs" != "$out" ]; then
  cp -R "$case_abs"/. "$out"/ || die "cannot copy $case_dir into $out"
fi
rm -f "$out"/fem.endpoint "$out"/dem.endpoint "$out"/*.endpoint.tmp

# ---- --set overrides, applied to the copies with Python's json module ----------------------
if [ ${#sets[@]} -gt 0 ]; then
  "$python" - "$out" "${sets[@]}" <<'PY' || exit 2
import json, sys
out, sets = sys.argv[1], sys.argv[2:]
docs = {}
for s in sets:
    if "=" not in s or "." not in s.split("=", 1)[0]:
        sys.exit("run_case: --set %r: expected FILE.KEY=VALUE, e.g. coupler.dt=0.001" % s)
    lhs, raw = s.split("=", 1)
    name, *keys = lhs.split(".")
    if name not in ("fem", "dem", "coupler"):
        sys.exit("run_case: --set %r: FILE must be fem, dem or coupler" % s)
    path = "%s/%s.json" % (out, name)
    if name not in docs:
        try:
            with open(path) as f:
                docs[name] = json.load(f)
        except (OSError, ValueError) as e:
            sys.exit("run_case: %s: %s" % (path, e))
    try:
        value = json.loads(raw)
    except ValueError:
        value = raw
    node = docs[name]
    for i, key in enumerate(keys):
        last = i == len(keys) - 1
        if isinstance(node, list):
            if not key.isdigit() or int(key) >= len(node):
                sys.exit("run_case: --set %r: '%s' is not an index of a list of %d items"
                         % (s, key, len(node)))
            key = int(key)
        elif not isinstance(node, dict):
            sys.exit("run_case: --set %r: '%s' is inside a %s, not an object or list"
                     % (s, key, type(node).__name__))
        if last:
            node[key] = value
        else:
            if isinstance(node, dict) and key not in node:
                node[key] = {}
            node = node[key]
for name, doc in docs.items():
    with open("%s/%s.json" % (out, name), "w") as f:
        json.dump(doc, f, indent=2)
        f.write("\n")
PY
fi

# ---- start the participants -----------------------------------------------------------
fem_pid=""; dem_pid=""; cpl_pid=""
cleanup() {
  for pid in $cpl_pid $fem_pid $dem_pid; do
    if kill -0 "$pid" 2>/dev/null; then kill -TERM "$pid" 2>/dev/null; fi
  done
  sleep 0.5
  for pid in $cpl_pid $fem_pid $dem_pid; do
    if kill -0 "$pid" 2>/dev/null; then kill -KILL "$pid" 2>/dev/null; fi
  done
}
interrupted=0
on_signal() {
  interrupted=1
  # the coupler shuts the solvers down itself; give it a moment
  [ -n "$cpl_pid" ] && kill -INT "$cpl_pid" 2>/dev/null
}
trap cleanup EXIT
trap on_signal INT TERM

# commands run inside $out: make relative paths in them absolute first
absolute_words() {
  local word result=""
  for word in $1; do
    if [ "${word#/}" = "$word" ] && [ -e "$word" ]; then word="$(pwd)/$word"; fi
    result="$result $word"
  done
  echo "${result# }"
}
fem_program=$(absolute_words "$fem_program")
dem_program=$(absolute_words "$dem_program")
cd "$out" || die "$out: cannot enter"
# shellcheck disable=SC2086   # the program may be a command with arguments
$fem_program fem.json --endpoint 'tcp://127.0.0.1:*' --output . --endpoint-file fem.endpoint \
  >fem.log 2>&1 &
fem_pid=$!
# shellcheck disable=SC2086
$dem_program dem.json --endpoint 'tcp://127.0.0.1:*' --output . --endpoint-file dem.endpoint \
  >dem.log 2>&1 &
dem_pid=$!

wait_endpoint() {   # name pid file
  local waited=0
  while [ ! -s "$3" ]; do
    if ! kill -0 "$2" 2>/dev/null; then
      wait "$2"; local rc=$?
      echo "run_case: $1 exited (status $rc) before publishing its endpoint; last lines of $out/$1.log:" >&2
      tail -n 15 "$1.log" >&2
      exit 1
    fi
    sleep 0.05; waited=$((waited + 1))
    if [ $waited -gt 1200 ]; then
      echo "run_case: $1 did not publish its endpoint in 60 s (see $out/$1.log)" >&2; exit 1
    fi
  done
}
wait_endpoint fem "$fem_pid" fem.endpoint
wait_endpoint dem "$dem_pid" dem.endpoint

quiet_arg=""; [ $quiet -eq 1 ] && quiet_arg="--quiet"
: >coupler.log
"$bin/coupler" coupler.json --output . --fem-endpoint "$(cat fem.endpoint)" \
  --dem-endpoint "$(cat dem.endpoint)" $quiet_arg >coupler.log 2>&1 &
cpl_pid=$!
if [ $quiet -eq 0 ]; then
  tail -n +1 -f coupler.log --pid="$cpl_pid" 2>/dev/null &
  tail_pid=$!
fi

# wait for the coupler (again after a signal interrupted the wait)
while :; do
  wait "$cpl_pid"; cpl_rc=$?
  kill -0 "$cpl_pid" 2>/dev/null || break
done
[ $quiet -eq 0 ] && { sleep 0.2; kill "$tail_pid" 2>/dev/null; wait "$tail_pid" 2>/dev/null; }
# the solvers exit after SHUTDOWN; give them time to close their files
# (after a coupler failure the healthy ones were told to shut down too; a dead coupler could
# not, so they get less time)
grace=600; [ "$cpl_rc" -ne 0 ] && [ "$cpl_rc" -ne 3 ] && grace=200
wait_exit() {   # pid -> exit status (killed after the grace time, 30 s or 10 s)
  local i=0
  while kill -0 "$1" 2>/dev/null && [ $i -lt $grace ]; do sleep 0.05; i=$((i + 1)); done
  kill -0 "$1" 2>/dev/null && kill -KILL "$1" 2>/dev/null
  wait "$1"
}
wait_exit "$fem_pid"; fem_rc=$?
wait_exit "$dem_pid"; dem_rc=$?
cpl_pid=""; fem_pid=""; dem_pid=""

# coupler exit 3: it finished, but accepted unconverged steps or created energy (not a
# failure of a program)
failed=()
[ "$cpl_rc" -ne 0 ] && [ "$cpl_rc" -ne 3 ] && failed+=("coupler (exit $cpl_rc, see $out/coupler.log)")
[ "$fem_rc" -ne 0 ] && failed+=("fem (exit $fem_rc, see $out/fem.log)")
[ "$dem_rc" -ne 0 ] && failed+=("dem (exit $dem_rc, see $out/dem.log)")
if [ ${#failed[@]} -gt 0 ]; then
  echo "run_case: failed: ${failed[*]}" >&2
  [ "$cpl_rc" -ne 0 ] && grep -m 3 "error" coupler.log >&2
  [ $interrupted -eq 1 ] && exit 130
  exit 1
fi
# the coupler's verdict (the last line of its summary) also when an accept_* key let it
# exit 0: such a run is never reported as done
if [ "$cpl_rc" -eq 3 ] || grep -q "results are NOT reliable" coupler.log; then
  echo "run_case: finished, but the results are NOT reliable; results in $out" >&2
  grep "results are NOT reliable" coupler.log >&2
  exit "$cpl_rc"
fi
echo "run_case: done, results in $out"
exit 0
