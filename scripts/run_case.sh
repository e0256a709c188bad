#!/bin/bash
# run_case.sh — run one coupled case: fem_solver + dem_solver + coupler on localhost.
# `run_case.sh --help` prints the usage below; README.md and coupler/README.md
# ("scripts/run_case.sh") say more.
#
# Supervision: the three programs are polled every 0.1 s, and their end is noticed at once
# (they hold the write end of a pipe whose read end run_case.sh waits on). The first one
# that fails is named as failed, the others as stopped: a solver that exits before the
# coupler told it to stop (also
# before the handshake), a coupler whose progress file (--progress-file, its heartbeat) is
# older than the stall limit, or the coupler's own error naming a participant. Everything
# still running is then stopped at once: SIGTERM (and SIGCONT, for a stopped process) to all,
# SIGKILL after the grace time.
set -u
# Every fork costs a few ms (about 4 on a small virtual machine, and the supervision loop runs
# beside the solvers on the same cores): folders are made absolute, files read and pauses
# taken with builtins, and external programs run only where there is no builtin.
abs_dir() {   # DIR -> REPLY: its absolute path (no subshell); 1 if it cannot be entered
  local here=$PWD
  builtin cd -- "$1" 2>/dev/null || return 1
  REPLY=$PWD
  builtin cd -- "$here" || return 1
}
case $0 in */*) abs_dir "${0%/*}/.." ;; *) abs_dir .. ;; esac
root=$REPLY
bin=${NC_BIN:-$root/bin}
python=/usr/bin/python3
# The three processes take turns on the same cores: OpenMP threads that spin while waiting
# (the default) steal the CPU from the process that is working (100x slower runs).
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
# OpenBLAS's worker threads (the dense kernels of CHOLMOD and LAPACK, in each of the three
# processes) otherwise spin on sched_yield for about 2^28 cycles after every call: a short
# wait before they sleep (the MEL test with the compliance over 0.1 s: 28-32 -> 22-23 s, two
# such runs at once 36 -> 24 s; as committed over 0.3 s the same 59-62 s).
export OPENBLAS_THREAD_TIMEOUT=${OPENBLAS_THREAD_TIMEOUT:-4}

usage() {
  cat <<'EOF'
usage: scripts/run_case.sh CASE_DIR [--out DIR] [--set FILE.KEY=VALUE ...]
                           [--fem-program CMD] [--dem-program CMD] [--quiet]
                           [--stall-limit SECONDS]
       scripts/run_case.sh --resume DIR [--fem-program CMD] [--dem-program CMD] [--quiet]
                           [--stall-limit SECONDS]
Runs one coupled case: fem_solver, dem_solver and the coupler on localhost.

CASE_DIR holds fem.json, dem.json, coupler.json and whatever they refer to (meshes, STL).
Everything is copied into DIR (default: runs/<case>-<date-time>; an earlier run's results in
DIR are replaced, as is said), --set overrides are applied to the copies, and all results land
there: fem.h5, dem.h5, coupling.h5, their XDMF files, iterations.log, one log per program
(fem.log, dem.log, coupler.log) and coupler.progress (the coupler's last state and status).
  --set FILE.KEY=VALUE    e.g. --set coupler.scheme=weak --set dem.materials.0.restitution=0.2
                          (numbers index lists, also as materials[0]; VALUE is JSON if it
                          parses as JSON, else a string)
  --fem-program CMD       replace a solver by another participant taking the same arguments
  --dem-program CMD       (e.g. "/usr/bin/python3 'my dir/plate.py'", split as a shell would)
  --quiet                 print only warnings, errors and the verdict
  --stall-limit SECONDS   stop the coupler as stalled when its heartbeat is older than this
                          (default 75, or $NC_STALL_LIMIT_S)
  --resume DIR            continue a stopped or crashed run in DIR from its last complete
                          checkpoint (coupler.json "checkpoint"; old logs kept as *.log.N)
Progress: on a terminal a live status line (time, remaining wall time, contact, rock speed and
energy, net deflection, iterations) under the coupler's messages; else the coupler's log.
The solvers bind free ports (tcp://127.0.0.1:*) and publish them in DIR/*.endpoint, so
parallel runs never collide; the coupler, started with them, reads them from there. Programs
come from $NC_BIN if set, else <repo>/bin.
$NC_STOP_GRACE_S (default 3): seconds between SIGTERM and SIGKILL when programs are stopped.
$NC_ENDPOINT_WAIT_S (default 60): how long a solver may go silent before its endpoint.
Exit status: 0 all three programs succeeded; 3 the run finished but accepted unconverged steps,
created energy or lost impulse at the interface (results NOT reliable; 0 with coupler.json
"accept_unconverged" / "accept_energy_growth" / "accept_impulse_loss": true, still NOT
reliable); 1 a program failed (named, the others stopped) or stalled; 2 bad arguments or case
(the programs check their inputs with --check before any starts; not a --fem-program or
--dem-program replacement), or --resume DIR without a complete checkpoint; 130 stopped by the
user (Ctrl-C or SIGTERM), all programs stopped, the results so far readable. A finished run
whose ropes exceeded breaking_load_n lists the FEM's warnings before "done" (no rope failure
in the model; exit 0), or with fem.json "analysis": {"fail_on_overload": true} ends NOT
reliable with exit 3 (a solver's own exit 3 after a finished coupling is such a verdict).
EOF
}

die() { echo "run_case: $*" >&2; exit 2; }

declare -A check_pid=()   # the input checks (below), by program
case_dir=""; out=""; sets=(); quiet=0; resume_dir=""; fem_given=0; dem_given=0
stall_limit=${NC_STALL_LIMIT_S:-75}; grace=${NC_STOP_GRACE_S:-3}; endpoint_wait=${NC_ENDPOINT_WAIT_S:-60}
fem_program="$bin/fem_solver"; dem_program="$bin/dem_solver"
while [ $# -gt 0 ]; do
  case "$1" in
    --out) [ $# -ge 2 ] || die "--out needs a folder"; out=$2; shift 2 ;;
    --set) [ $# -ge 2 ] || die "--set needs FILE.KEY=VALUE"; sets+=("$2"); shift 2 ;;
    --fem-program) [ $# -ge 2 ] || die "--fem-program needs a command"; fem_program=$2; fem_given=1; shift 2 ;;
    --dem-program) [ $# -ge 2 ] || die "--dem-program needs a command"; dem_program=$2; dem_given=1; shift 2 ;;
    --resume) [ $# -ge 2 ] || die "--resume needs the folder of the run"; resume_dir=$2; shift 2 ;;
    --quiet) quiet=1; shift ;;
    --stall-limit) [ $# -ge 2 ] || die "--stall-limit needs seconds"; stall_limit=$2; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    -*) die "unknown option $1 (see --help)" ;;
    *) [ -z "$case_dir" ] || die "only one CASE_DIR, got '$case_dir' and '$1'"; case_dir=$1; shift ;;
  esac
done
if [ -n "$resume_dir" ]; then
  [ -z "$case_dir" ] || die "--resume continues the run in $resume_dir with its own inputs: no CASE_DIR ('$case_dir')"
  [ -z "$out" ] || die "--resume writes into the run's own folder $resume_dir: no --out"
  [ ${#sets[@]} -eq 0 ] || die "--resume continues with the inputs the run started with: no --set"
  [ -d "$resume_dir" ] || die "$resume_dir: no such run folder"
  for f in fem.json dem.json coupler.json; do
    [ -f "$resume_dir/$f" ] || die "$resume_dir/$f: missing (not the folder of a run)"
  done
  # the last complete checkpoint: the manifest and the three files it names
  "$python" - "$resume_dir" <<'PY' || exit 2
import json, os, sys
d = sys.argv[1]
path = os.path.join(d, "checkpoint", "latest.json")
def no(why):
    sys.exit("run_case: --resume %s: no complete checkpoint: %s" % (d, why))
if not os.path.isfile(path):
    no("%s is missing (the run wrote no checkpoint: coupler.json needs \"checkpoint\": "
       "{\"interval_s\": ...} and both participants must announce 'checkpoint')" % path)
try:
    with open(path) as f:
        m = json.load(f)
    name, files = m["checkpoint"], m["files"]
    names = [files[k] for k in ("coupler", "fem", "dem")]
except (OSError, ValueError, KeyError, TypeError) as e:
    no("%s is not a checkpoint manifest (%s: %s)" % (path, type(e).__name__, e))
for k, f in zip(("coupler", "fem", "dem"), names):
    if not isinstance(f, str) or "/" in f or not os.path.isfile(os.path.join(d, "checkpoint", f)):
        no("%s names the %s file %r, which is not in %s/checkpoint" % (path, k, f, d))
PY
  case_dir=$resume_dir; out=$resume_dir
fi
[ -n "$case_dir" ] || die "usage: run_case.sh CASE_DIR [--out DIR] [--set FILE.KEY=VALUE ...] (see --help)"
positive='^[0-9]+([.][0-9]+)?$'
[[ $stall_limit =~ $positive ]] && [[ $stall_limit != 0 ]] \
  || die "--stall-limit / NC_STALL_LIMIT_S: expected seconds > 0, got '$stall_limit'"
[[ $grace =~ $positive ]] || die "NC_STOP_GRACE_S: expected seconds >= 0, got '$grace'"
[[ $endpoint_wait =~ $positive ]] || die "NC_ENDPOINT_WAIT_S: expected seconds >= 0, got '$endpoint_wait'"
[ -d "$case_dir" ] || die "$case_dir: no such case folder"
for f in fem.json dem.json coupler.json; do
  [ -f "$case_dir/$f" ] || die "$case_dir/$f: missing (a case folder holds fem.json, dem.json, coupler.json)"
done
for program in coupler netcouple-set; do
  [ -x "$bin/$program" ] || die "$bin/$program not found (build with make, or set NC_BIN)"
done
abs_dir "$bin" || die "$bin: cannot enter the programs' folder"
bin=$REPLY
[ "$fem_program" = "$root/bin/fem_solver" ] && fem_program="$bin/fem_solver"
[ "$dem_program" = "$root/bin/dem_solver" ] && dem_program="$bin/dem_solver"
abs_dir "$case_dir" || die "$case_dir: cannot enter the case folder"
case_abs=$REPLY
[ -n "$out" ] || printf -v out 'runs/%s-%(%Y%m%d-%H%M%S)T' "${case_abs##*/}" -1
parent=.; [[ $out == */* ]] && parent=${out%/*}
if [ -z "$resume_dir" ] && [ ! -e "$out" ] && [ -d "${parent:-/}" ]; then
  # a new folder in an existing one: cp makes it as the copy (one process instead of two;
  # -H: a case folder given as a symbolic link is copied, not the link), writable whatever
  # the case folder's own mode
  cp -RH "$case_abs" "$out" || die "cannot copy $case_dir into $out"
  [ -w "$out" ] || chmod u+w "$out" || die "$out: cannot make the output folder writable"
  abs_dir "$out" || die "$out: cannot enter the output folder"
  out=$REPLY
else
  [ -d "$out" ] || mkdir -p "$out" || die "$out: cannot create the output folder"
  abs_dir "$out" || die "$out: cannot enter the output folder"
  out=$REPLY
  if [ -z "$resume_dir" ] && [ -e "$out/coupling.h5" ]; then
    echo "run_case: $out holds an earlier run's results: they are replaced (a new --out folder keeps them)" >&2
  fi
  if [ -z "$resume_dir" ] && [ "$case_abs" != "$out" ]; then
    cp -R "$case_abs"/. "$out"/ || die "cannot copy $case_dir into $out"
  fi
fi
remove_files() {   # FILE...: rm -f, run only when one of them exists
  local f
  for f in "$@"; do
    if [ -e "$f" ] || [ -L "$f" ]; then rm -f -- "$@"; return; fi
  done
}
remove_files "$out"/fem.endpoint "$out"/dem.endpoint "$out"/*.endpoint.tmp

# ---- --set overrides, applied to the copies (coupler/set/netcouple_set.c) ---------------
if [ ${#sets[@]} -gt 0 ]; then
  "$bin/netcouple-set" "$out" "${sets[@]}" || exit 2
fi

# ---- supervision helpers ----------------------------------------------------------------
# pid[P] and rc[P] for P in fem, dem, coupler; rc is "" while P runs.
declare -A pid=() rc=()
programs=(fem dem coupler)
failed=""; failed_why=""   # the first program that failed, and how
interrupted=""             # INT or TERM once the user stopped run_case.sh

now_ms() { local t=$EPOCHREALTIME; NOW_MS=$(( ${t%[.,]*} * 1000 + 10#${t#*[.,]} / 1000 )); }
ms() {   # VAR SECONDS: VAR = SECONDS in milliseconds
  local x=$2; [[ $x == *.* ]] || x="$x."; local f=${x#*.}000
  printf -v "$1" '%d' $(( ${x%.*} * 1000 + 10#${f:0:3} ))
}
ms grace_ms "$grace"; ms stall_ms "$stall_limit"
# the heartbeat's age is looked at (a `stat`) every tenth of the stall limit, at most every 1 s
beat_every_ms=$((stall_ms / 10)); [ $beat_every_ms -le 1000 ] || beat_every_ms=1000
# nap SECONDS: a pause without a process, a read with a timeout on a pipe that never has data
# (nap_fd, held open read-write by this shell from the start of the programs); sleep without it
nap_fd=""; alive_fd=""   # (the pipes are made where the programs start)
nap() {
  if [ -n "$nap_fd" ]; then read -r -t "$1" -u "$nap_fd" _; else sleep "$1"; fi
  return 0
}
pause() {   # 0.1 s, cut short when the last program ends; 0.01 s once they have (or no pipe)
  if [ -n "$alive_fd" ]; then
    local byte
    read -r -t 0.1 -u "$alive_fd" byte
    [ $? -gt 128 ] && return 0
    exec {alive_fd}<&-; alive_fd=""   # all three have ended (they never write)
    return 0
  fi
  nap 0.01
}

reap() {   # collects the exit status of every program that has ended
  local p
  for p in "${programs[@]}"; do
    if [ -n "${pid[$p]:-}" ] && [ -z "${rc[$p]:-}" ] && ! kill -0 "${pid[$p]}" 2>/dev/null; then
      wait "${pid[$p]}"; rc[$p]=$?
    fi
  done
}
any_running() {   # status 0 while one of the programs runs
  local p
  for p in "${programs[@]}"; do
    [ -n "${pid[$p]:-}" ] && [ -z "${rc[$p]:-}" ] && return 0
  done
  return 1
}
# running and how answer in REPLY: a $(...) costs a process, and the launcher's own time is
# paid by every run
running() {   # REPLY = names of the programs still running
  local p out=""
  for p in "${programs[@]}"; do
    [ -n "${pid[$p]:-}" ] && [ -z "${rc[$p]:-}" ] && out="$out $p"
  done
  REPLY=${out# }
}
how() {   # P -> REPLY = "exit 1", "exit 137 = SIGKILL" (killed, or exited so), "running"
  local r=${rc[$1]:-}
  if [ -z "$r" ]; then REPLY="running"
  # a participant's own exit status after either stop signal (protocol/README.md §6), also
  # after the SIGTERM this script sends: not a sign of SIGINT
  elif [ "$r" -eq 130 ] && [ "$1" != coupler ]; then REPLY="exit 130: stopped by SIGINT or SIGTERM"
  elif [ "$r" -gt 128 ] && [ "$r" -lt 160 ]; then REPLY="exit $r = SIG$(kill -l $((r - 128)))"
  else REPLY="exit $r"; fi
}
log_has() {   # FILE TEXT: status 0 when FILE exists and has TEXT in it (without a process)
  local lines=()
  [ -f "$1" ] || return 1
  mapfile -t lines < "$1"
  [[ "${lines[*]}" == *"$2"* ]]
}
fail_first() {   # P WHY: P is the first program that failed (later calls change nothing)
  [ -n "$failed" ] && return 0
  failed=$1; failed_why=$2
}
stop_all() {   # SIGTERM to every running program at once, SIGKILL after the grace time
  local p list
  reap; any_running || return 0
  running; list=$REPLY
  for p in $list; do kill -TERM "${pid[$p]}" 2>/dev/null; kill -CONT "${pid[$p]}" 2>/dev/null; done
  now_ms; local until=$((NOW_MS + grace_ms))
  while any_running && [ "$NOW_MS" -lt "$until" ]; do nap 0.01; reap; now_ms; done
  running; for p in $REPLY; do kill -KILL "${pid[$p]}" 2>/dev/null; done
  running; for p in $REPLY; do wait "${pid[$p]}"; rc[$p]=$?; done
}
wait_all_exit() {   # MS [any]: waits until every program has ended, at most MS milliseconds
  now_ms; local until=$((NOW_MS + $1))   # (without "any", a Ctrl-C ends the wait)
  reap
  while any_running && [ "$NOW_MS" -lt "$until" ] && { [ -z "$interrupted" ] || [ -n "${2:-}" ]; }; do
    pause; reap; now_ms
  done
}
on_signal() { interrupted=$1; }
trap 'on_signal INT' INT
trap 'on_signal TERM' TERM
trap 'stop_all' EXIT   # whatever happens, no program outlives run_case.sh

# the coupler's progress file: "state ...", "status ...", "waiting ..." lines
cpl_state=""; cpl_status=""
read_progress() {
  local key rest
  cpl_state=""; cpl_status=""
  [ -f coupler.progress ] || return 0
  while IFS=' ' read -r key rest; do
    case "$key" in state) cpl_state=$rest ;; status) cpl_status=$rest ;; esac
  done < coupler.progress
}

# the final report; exits
report() {
  local p others=""
  stop_all
  [ -n "${show_pid:-}" ] && { kill "$show_pid" 2>/dev/null; wait "$show_pid" 2>/dev/null; }
  [ "$status_shown" -eq 1 ] && printf '\r\033[K'
  trap - EXIT
  for p in "${programs[@]}"; do
    [ -n "${pid[$p]:-}" ] && { [ "$p" != "$failed" ] || [ -n "$interrupted" ]; } \
      && how "$p" && others="$others, $p ($REPLY)"
  done
  others=${others#, }
  if [ -n "$interrupted" ]; then
    echo "run_case: stopped by user (SIG$interrupted)${others:+; stopped: $others}; results so far in $out" >&2
    exit 130
  fi
  if [ -n "$failed" ]; then
    echo "run_case: failed: $failed ($failed_why, see $out/$failed.log)${others:+; stopped: $others}" >&2
    if [ -f coupler.log ] && grep -q "error" coupler.log; then grep -m 3 "error" coupler.log >&2; fi
    if [ "$failed" != coupler ] && [ -f "$failed.log" ]; then
      echo "run_case: last lines of $out/$failed.log:" >&2; tail -n 10 "$failed.log" >&2
    fi
    # a full disk takes the program's own message with it: its log stays empty (a program
    # killed by a signal leaves it empty too, with room on the disk)
    if [ -f "$failed.log" ] && [ ! -s "$failed.log" ]; then
      free_k=""; mount_point=""   # (a command substitution: waited for, unlike <(...))
      read -r free_k mount_point <<< "$(df -kP . 2>/dev/null | awk 'NR == 2 {print $4, $6}')"
      if [[ $free_k =~ ^[0-9]+$ ]] && [ "$free_k" -lt 1024 ]; then
        echo "run_case: $out/$failed.log is empty: $failed's messages could not be written" \
             "($free_k kB free on $mount_point: a full disk)" >&2
      else
        echo "run_case: $out/$failed.log is empty: $failed wrote no message" >&2
      fi
    fi
    exit 1
  fi
  # the structure's ropes above their breaking load: a right answer for ropes that do not
  # break, which real ones would; the FEM's warnings say which sets, how far and when
  if log_has fem.log "exceeded breaking_load_n"; then
    echo "run_case: ropes above their breaking load (the model has no rope failure):" >&2
    grep "exceeded breaking_load_n" fem.log | sed 's/^fem_solver: warning: /  /' >&2
  fi
  # the programs' warnings about their input (a value outside its plausible range: a modulus
  # in GPa written in Pa, a diameter in mm; an option the run's set-up leaves without
  # effect): the run went on with the input as given, and the warnings sit in the logs,
  # which run_case.sh does not show while it runs (nor the coupler's with --quiet)
  input_warnings=$( { grep -h "^warning: [^ ]*\.json: " fem.log dem.log
                      grep -h "^coupler: warning: [^ ]*\.json: " coupler.log | sed 's/^coupler: //'
                    } 2>/dev/null)
  if [ -n "$input_warnings" ]; then
    echo "run_case: the programs warned about their input (the results are those of the input as given):" >&2
    sed 's/^warning: /  /' <<< "$input_warnings" >&2
  fi
  # the coupler's verdict (the last line of its summary) also when an accept_* key let it
  # exit 0: such a run is never reported as done
  if [ "${rc[coupler]:-}" -eq 3 ] || log_has coupler.log "results are NOT reliable" || [ -n "$unreliable" ]; then
    echo "run_case: finished, but the results are NOT reliable; results in $out" >&2
    grep "results are NOT reliable" coupler.log >&2
    for p in $unreliable; do   # the solver's last line says why
      echo "run_case: $p exited with 3: $(tail -n 1 "$p.log")" >&2
    done
    [ -n "$unreliable" ] && exit 3
    exit "${rc[coupler]:-}"
  fi
  if [ -n "$input_warnings" ]; then
    echo "run_case: done, with the warnings about the input above; results in $out"
  else
    echo "run_case: done, results in $out"
  fi
  exit 0
}

# The solvers' commands as words: a built-in program is one word (a folder with spaces in its
# name included); a --fem-program / --dem-program command is split as the shell would split it,
# quotes and backslashes kept ("/usr/bin/python3 'my dir/plate.py'" is two words). Commands
# run inside $out: relative paths in them are made absolute first.
command_words() {   # ARRAY COMMAND
  local -n words_=$1
  local split
  if [[ $2 == *[\"\'\\]* ]]; then
    split=$("$python" -c 'import shlex, sys; print("\n".join(shlex.split(sys.argv[1])))' "$2" 2>/dev/null) \
      || die "cannot split the command '$2' into words (unbalanced quotes?)"
    mapfile -t words_ <<< "$split"
  else
    read -ra words_ <<< "$2"
  fi
  [ ${#words_[@]} -gt 0 ] || die "an empty program command"
}
absolute_words() {   # ARRAY: its words that name existing files made absolute
  local -n words_=$1
  local k
  for k in "${!words_[@]}"; do
    if [ "${words_[k]#/}" = "${words_[k]}" ] && [ -e "${words_[k]}" ]; then
      words_[k]="$PWD/${words_[k]}"
    fi
  done
}
fem_cmd=("$fem_program"); dem_cmd=("$dem_program")
[ $fem_given -eq 0 ] || command_words fem_cmd "$fem_program"
[ $dem_given -eq 0 ] || command_words dem_cmd "$dem_program"
absolute_words fem_cmd
absolute_words dem_cmd
cd "$out" || die "$out: cannot enter"
# the programs of a run, for --resume (which starts the same ones unless told otherwise),
# one line each: the role, then the command's words quoted as the shell reads them
if [ -n "$resume_dir" ]; then
  if [ -f run_case.programs ]; then
    { IFS= read -r saved_fem; IFS= read -r saved_dem; } < run_case.programs
    [ $fem_given -eq 1 ] || command_words fem_cmd "${saved_fem#fem }"
    [ $dem_given -eq 1 ] || command_words dem_cmd "${saved_dem#dem }"
  fi
  # the earlier run's logs stay, numbered
  n=1; while [ -e "coupler.log.$n" ] || [ -e "fem.log.$n" ] || [ -e "dem.log.$n" ]; do n=$((n + 1)); done
  for p in fem dem coupler; do [ -f "$p.log" ] && mv "$p.log" "$p.log.$n"; done
fi
printf -v fem_line '%q ' "${fem_cmd[@]}"; printf -v dem_line '%q ' "${dem_cmd[@]}"
printf 'fem %s\ndem %s\n' "${fem_line% }" "${dem_line% }" > run_case.programs

# ---- the inputs, checked before anything starts ------------------------------------------
# Each program reads and checks its input with --check (all three at once): a mistake in the
# case or in a --set value stops here with exit 2, naming the file and the key, instead of
# one program failing after the others started. Another solver (--fem-program,
# --dem-program, or the one a resumed run was started with) checks its own input when it
# starts: only netcouple's fem_solver and dem_solver are asked.
check_pid=()
check_input() {   # NAME WORDS...: WORDS --check in the background, its stderr in NAME.check
  local name=$1; shift
  ( exec "$@" --check > /dev/null 2> "$name.check" ) &
  check_pid[$name]=$!
}
[ ${#fem_cmd[@]} -eq 1 ] && [ "${fem_cmd[0]##*/}" = fem_solver ] &&
  check_input fem "${fem_cmd[0]}" fem.json --endpoint 'tcp://127.0.0.1:*'
[ ${#dem_cmd[@]} -eq 1 ] && [ "${dem_cmd[0]##*/}" = dem_solver ] &&
  check_input dem "${dem_cmd[0]}" dem.json --endpoint 'tcp://127.0.0.1:*'
check_input coupler "$bin/coupler" coupler.json
bad_input=0
for name in fem dem coupler; do
  [ -n "${check_pid[$name]:-}" ] || continue
  if ! wait "${check_pid[$name]}"; then
    echo "run_case: $name: its input is not valid, nothing was started:" >&2
    grep -v "^warning: " "$name.check" >&2
    bad_input=1
  fi
  rm -f "$name.check"
done
[ $bad_input -eq 0 ] || exit 2

remove_files coupler.progress coupler.progress.tmp
status_shown=0; show_pid=""

# ---- start the solvers -------------------------------------------------------------------
# A run_case.sh killed with SIGKILL cannot stop its programs: each gets SIGTERM from the kernel
# when run_case.sh dies (setpriv --pdeathsig, util-linux), instead of waiting for a coupler
# that never comes until its idle timeout.
guard=()
# (looked up, not tried: util-linux has had --pdeathsig since 2.33, Debian 10 and Ubuntu
# 20.04; an older setpriv fails every program at its start, naming the option)
type -P setpriv >/dev/null 2>&1 && guard=(setpriv --pdeathsig TERM)
# Two pipes, each from a process substitution (a fork without an exec, and no file to make or
# remove), opened again through /dev/fd for the ends wanted:
# - nap_fd, held open read-write by this shell: it never has data (nap);
# - alive_fd: the three programs alone will hold its write end (alive_w), so a read of alive_fd
#   returns at once when all three have ended (a coupler that finished tells the solvers to
#   stop, and they end with it), instead of at the next poll.
# The programs get only alive_w.
alive_fd=""; alive_w=""
if ! { exec {nap_fd}<> <(:) {pipe_fd}<> <(:) {alive_w}>"/dev/fd/$pipe_fd" {alive_fd}<"/dev/fd/$pipe_fd" \
         {pipe_fd}>&-; } 2>/dev/null; then   # no /dev/fd: polled, and pauses with sleep
  nap_fd=""; alive_fd=""; alive_w=""
fi
exec_closing() {   # "FD ..." CMD...: execs CMD with this shell's file descriptors FD closed
  local fd
  for fd in $1; do eval "exec $fd>&-"; done
  shift
  exec "$@"
}
exec_closing "$nap_fd $alive_fd" "${guard[@]}" "${fem_cmd[@]}" fem.json \
  --endpoint 'tcp://127.0.0.1:*' --output . --endpoint-file fem.endpoint >fem.log 2>&1 &
pid[fem]=$!
exec_closing "$nap_fd $alive_fd" "${guard[@]}" "${dem_cmd[@]}" dem.json \
  --endpoint 'tcp://127.0.0.1:*' --output . --endpoint-file dem.endpoint >dem.log 2>&1 &
pid[dem]=$!

# ---- the coupler, started with them: it reads their endpoints as they appear ---------------
quiet_arg=""; [ $quiet -eq 1 ] && quiet_arg="--quiet"
resume_arg=""; [ -n "$resume_dir" ] && resume_arg="--resume"
: >coupler.log
# This script decides when a solver that has not published its endpoint has failed (below:
# one that keeps writing to its log is still starting, a large barrier settling for minutes),
# so the coupler is told to wait a day: it never gives up first.
ms endpoint_wait_ms "$endpoint_wait"
coupler_wait=86400
# shellcheck disable=SC2206   # the empty arguments vanish
coupler_cmd=("${guard[@]}" "$bin/coupler" coupler.json --output . --fem-endpoint-file fem.endpoint
             --dem-endpoint-file dem.endpoint --endpoint-wait "$coupler_wait"
             --progress-file coupler.progress $quiet_arg $resume_arg)
# the coupler inherits alive_w too, and this shell closes its own
exec_closing "$nap_fd $alive_fd" "${coupler_cmd[@]}" >coupler.log 2>&1 &
pid[coupler]=$!
[ -z "$alive_w" ] || exec {alive_w}>&-

# ---- the solvers' endpoints (or the coupler ended, e.g. on a bad coupler.json) -------------
# a solver without an endpoint fails after NC_ENDPOINT_WAIT_S without a new line in its log
# (fem_solver reports the progress of a long initial equilibrium every few seconds)
now_ms; told_ms=""
declare -A log_size=([fem]=-1 [dem]=-1) log_grew_ms=([fem]=$NOW_MS [dem]=$NOW_MS)
logs_checked_ms=0
while { [ ! -s fem.endpoint ] || [ ! -s dem.endpoint ]; } && [ -z "${rc[coupler]:-}" ]; do
  reap
  [ -n "${rc[coupler]:-}" ] && break
  now_ms
  for p in fem dem; do
    if [ -n "${rc[$p]:-}" ]; then
      # exit 0: told to go by a coupler that is stopping (it refused its coupler.json and
      # waits for the other solver's endpoint to tell it too): the coupler's verdict counts;
      # said before it stops, the solver is blamed after the grace time
      if [ "${rc[$p]}" -eq 0 ]; then
        read_progress
        [ "$cpl_state" = stopping ] && continue
        [ -n "$told_ms" ] || told_ms=$NOW_MS
        [ $((NOW_MS - told_ms)) -lt "$grace_ms" ] && continue
      fi
      how "$p"
      if [ -s "$p.endpoint" ]; then fail_first "$p" "$REPLY before the handshake"
      else fail_first "$p" "$REPLY before publishing its endpoint"; fi
    fi
  done
  [ -n "$failed" ] || [ -n "$interrupted" ] && report
  now_ms
  if [ $((NOW_MS - logs_checked_ms)) -ge 1000 ]; then   # (a stat a second, not each pause)
    logs_checked_ms=$NOW_MS
    for p in fem dem; do
      [ -s "$p.endpoint" ] && continue
      size=$(stat -c %s "$p.log" 2>/dev/null) || size=0
      if [ "$size" != "${log_size[$p]}" ]; then log_size[$p]=$size; log_grew_ms[$p]=$NOW_MS; fi
      [ $((NOW_MS - log_grew_ms[$p])) -le "$endpoint_wait_ms" ] ||
        fail_first "$p" "did not publish its endpoint, and wrote nothing to $p.log, in $endpoint_wait s (NC_ENDPOINT_WAIT_S)"
    done
    [ -n "$failed" ] && report
  fi
  nap 0.01
done

# ---- what the user sees --------------------------------------------------------------------
now_ms; cpl_started_ms=$NOW_MS

live=0
if [ $quiet -eq 0 ]; then
  if [ -t 1 ]; then
    # a terminal: the coupler's messages as they come, and its live status line under them
    live=1
    columns=$(tput cols 2>/dev/null || echo 80)
    exec 3< <(exec tail -n +1 -s 0.05 -f coupler.log --pid="${pid[coupler]}" 2>/dev/null)
    show_pid=$!
  else
    tail -n +1 -s 0.05 -f coupler.log --pid="${pid[coupler]}" 2>/dev/null &
    show_pid=$!
  fi
fi
shown_status=""; pending=""
log_line() {   # on a terminal: one line of the log above the status line
  # the periodic status lines of the log are what the live line shows; the final one (the
  # coupler says "finishing" or "stopping" before it) stays
  if [[ $1 == "t = "* ]]; then
    read_progress
    [ "$cpl_state" = running ] || [ "$cpl_state" = connecting ] && return 0
  fi
  [ "$status_shown" -eq 1 ] && printf '\r\033[K'
  status_shown=0
  printf '%s\n' "$1"
}
read_log() {   # TIMEOUT: the log lines that arrived; 1 at the end of the log
  local line r
  while :; do
    IFS= read -r -t "$1" -u 3 line; r=$?
    if [ $r -eq 0 ]; then log_line "$pending$line"; pending=""; continue; fi
    pending="$pending$line"   # a timeout keeps a partial line
    [ $r -gt 128 ] && return 0
    [ -n "$pending" ] && log_line "$pending"; pending=""
    return 1
  done
}
show() {   # new log lines, then the status line (a terminal); else just a pause
  if [ $live -eq 0 ] || [ -n "$log_ended" ]; then pause; return 0; fi
  read_log 0.1 || log_ended=1
  if [ -n "$cpl_status" ] && { [ "$status_shown" -eq 0 ] || [ "$cpl_status" != "$shown_status" ]; }; then
    printf '\r%s\033[K' "${cpl_status:0:$((columns - 1))}"
    status_shown=1; shown_status=$cpl_status
  fi
}
log_ended=""

# ---- supervision while the coupler runs ---------------------------------------------------
declare -A noticed_ms=() noticed_why=()
# (first looked at after beat_every_ms: a `stat` at once would take a core from the programs'
# start, and the heartbeat cannot be older than the stall limit yet)
beat_checked_ms=$((cpl_started_ms + beat_every_ms)); beat_ms=$cpl_started_ms
while :; do
  reap
  [ -n "${rc[coupler]:-}" ] && break
  if [ -n "$interrupted" ]; then
    # the coupler shuts the solvers down cleanly on a stop signal; a Ctrl-C on the terminal
    # has reached it already (it then says "stopping" at once), and a second signal would cut
    # its SHUTDOWN requests short: signal it only when it has not heard one
    for _ in 1 2 3 4 5 6; do
      reap; read_progress
      [ -n "${rc[coupler]:-}" ] || [ "$cpl_state" = stopping ] || [ "$cpl_state" = finishing ] && break
      nap 0.05
    done
    if [ -z "${rc[coupler]:-}" ] && [ "$cpl_state" != stopping ] && [ "$cpl_state" != finishing ]; then
      kill -TERM "${pid[coupler]}" 2>/dev/null
    fi
    wait_all_exit $((2 * grace_ms + 1000)) any
    report
  fi
  read_progress
  now_ms
  for p in fem dem; do
    # an exit is a failure unless the coupler told it to stop (it says so in its state
    # first); once it is stopping, a participant that answered errors exits 1 as it should
    # (protocol/README.md §6), and the coupler's own message names who failed
    if [ -n "${rc[$p]:-}" ] && [ -z "${noticed_ms[$p]:-}" ]; then
      if [ "$cpl_state" = connecting ] || [ "$cpl_state" = running ] || [ -z "$cpl_state" ]; then
        noticed_ms[$p]=$NOW_MS
        if [ "${rc[$p]:-}" -eq 0 ]; then noticed_why[$p]="exit 0 before the coupler told it to stop"
        else how "$p"; noticed_why[$p]="$REPLY while the coupler was ${cpl_state:-starting}"; fi
      fi
    fi
    # running, the coupler gets the grace time to notice by itself (its message names step
    # and iteration) and to end with its own verdict, which counts if it comes (a coupler
    # that could not write "stopping", its disk full, may have told the solver to stop);
    # connecting, it would only notice after its connect timeout
    if [ -n "${noticed_ms[$p]:-}" ] && { [ "$cpl_state" != running ] ||
                                         [ $((NOW_MS - noticed_ms[$p])) -ge "$grace_ms" ]; }; then
      fail_first "$p" "${noticed_why[$p]}"
      report
    fi
  done
  # the heartbeat: the progress file is rewritten every step and every second of a wait
  if [ "$NOW_MS" -ge "$beat_checked_ms" ]; then
    beat_checked_ms=$((NOW_MS + beat_every_ms))
    beat_ms=$cpl_started_ms
    if [ -f coupler.progress ]; then
      mtime=$(stat -c %.3Y coupler.progress 2>/dev/null)
      # (a Ctrl-C to the whole job may also have hit stat)
      [[ $mtime =~ ^[0-9]+([.][0-9]+)?$ ]] && ms beat_ms "$mtime"
    fi
    [ "$beat_ms" -lt "$cpl_started_ms" ] && beat_ms=$cpl_started_ms
  fi
  if [ -z "$interrupted" ] && [ $((NOW_MS - beat_ms)) -gt "$stall_ms" ]; then
    fail_first coupler "stalled: no heartbeat (coupler.progress) for $(( (NOW_MS - beat_ms) / 1000 )) s, limit $stall_limit s"
    report
  fi
  show
done

# ---- the coupler has ended: the solvers follow --------------------------------------------
if [ "${rc[coupler]:-}" -eq 0 ] || [ "${rc[coupler]:-}" -eq 3 ]; then
  # after SHUTDOWN they close their files; a solver still running after 30 s has hung
  wait_all_exit 30000
  running; for p in $REPLY; do fail_first "$p" "did not exit within 30 s after SHUTDOWN"; done
else
  error=$(grep -m 1 "^coupler: error: " coupler.log)
  # a Ctrl-C on the terminal reaches the coupler too, maybe before run_case.sh notices
  if [[ $error =~ ^coupler:\ error:\ interrupted\ by\ SIG(INT|TERM) ]] && [ -z "$failed" ]; then
    [ -n "$interrupted" ] || interrupted=${BASH_REMATCH[1]}
  fi
  if [ -n "$interrupted" ]; then   # it sent the solvers SHUTDOWN
    wait_all_exit "$grace_ms" any
    report
  fi
  how coupler
  if [ "${rc[coupler]:-}" -gt 128 ]; then
    fail_first coupler "$REPLY"   # it could tell no one: stop the solvers now
  elif [[ $error =~ ^coupler:\ error:\ (fem|dem)[:\ ] ]]; then
    fail_first "${BASH_REMATCH[1]}" "named by the coupler's error"   # printed below
  elif [[ $error =~ ^coupler:\ error:\ (.*) ]]; then
    fail_first coupler "$REPLY: ${BASH_REMATCH[1]}"
  else
    fail_first coupler "$REPLY"
  fi
  # the healthy solvers were told to shut down; they get the grace time
  [ "${rc[coupler]:-}" -gt 128 ] || wait_all_exit "$grace_ms"
fi
reap
unreliable=""   # solvers that finished the coupled run and judged its results NOT reliable
for p in fem dem; do
  # exit 3 after the coupler finished: the solver's own verdict (fem_solver: a rope above its
  # breaking load with analysis.fail_on_overload), not a failure of the program
  if [ "${rc[$p]:-}" = 3 ] && { [ "${rc[coupler]:-}" -eq 0 ] || [ "${rc[coupler]:-}" -eq 3 ]; }; then
    unreliable="$unreliable $p"
    continue
  fi
  [ -n "${rc[$p]:-}" ] && [ "${rc[$p]:-}" -ne 0 ] && how "$p" && fail_first "$p" "$REPLY"
done
if [ $live -eq 1 ]; then   # the rest of the log (tail ends within 0.05 s of the coupler)
  [ -n "$log_ended" ] || read_log 1
elif [ -n "$show_pid" ]; then
  for ((i = 0; i < 200; i++)); do kill -0 "$show_pid" 2>/dev/null || break; nap 0.01; done
fi
report
