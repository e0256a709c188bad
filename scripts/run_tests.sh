#!/usr/bin/env bash
# Runs every netcouple test and ends with one line "N passed, N failed".
#   scripts/run_tests.sh BUILD_TEST_DIR BIN_DIR [FILTER]
# - compiled cmocka programs: BUILD_TEST_DIR/<module>/test_*   (each cmocka test counts)
# - script tests: tests/<module>/test_*.sh and tests/<module>/test_*.py (each file counts once;
#   exit 0 = pass, 77 = skipped). They get NC_BIN (programs), NC_BUILD_TESTS and NC_TMP.
# FILTER (optional) is a substring a test path must contain.
# The case tests (tests/cases/: whole coupled runs, most of the suite's time; their limits are
# the launcher's, a 75 s stall and a 60 s reply) run NC_TEST_JOBS at a time (default: the number
# of cores), after every other test has run alone: those time replies, stalls and signals in
# seconds and must not share the machine.
set -u
build_tests=${1:?build test dir}
bin_dir=${2:?bin dir}
filter=${3:-${TEST_FILTER:-}}
case_jobs=${NC_TEST_JOBS:-$(nproc 2>/dev/null || echo 1)}
if ! [[ $case_jobs =~ ^[1-9][0-9]*$ ]]; then
  echo "NC_TEST_JOBS: expected a count >= 1, got '$case_jobs'"
  exit 2
fi
# wait -n -p (which job ended) needs bash 5.1; an older bash runs the case tests one at a time
if ((BASH_VERSINFO[0] * 100 + BASH_VERSINFO[1] < 501)); then case_jobs=1; fi
root=$(cd "$(dirname "$0")/.." && pwd)
PYTHON=/usr/bin/python3   # Debian's interpreter, which has python3-zmq/h5py/numpy
mkdir -p "$bin_dir"
export NC_BIN=$(cd "$bin_dir" && pwd)
export NC_BUILD_TESTS=$(cd "$build_tests" 2>/dev/null && pwd || echo "$build_tests")
export NC_ROOT=$root
export PYTHON
tmp_root=$(mktemp -d "${TMPDIR:-/tmp}/netcouple-tests.XXXXXX")
trap 'rm -rf "$tmp_root"' EXIT
declare -A pool_running=()   # the pids of the case tests running in the background (run_pool)
# Ctrl-C or a kill: the case tests running in the background go too, before their files do
trap '[ ${#pool_running[@]} -gt 0 ] && kill "${!pool_running[@]}" 2>/dev/null; wait; exit 130' INT TERM
passed=0; failed=0; skipped=0
failed_names=()
timings="$tmp_root/timings"   # "seconds name" per test file, for the slowest-tests list
: >"$timings"

run_cmocka() {
  local prog=$1 log
  log="$tmp_root/$(basename "$prog").log"
  echo "== $prog"
  local start=$SECONDS
  # cmocka prints "[  PASSED  ] N test(s)." and "[  FAILED  ] N test(s)..."
  NC_TMP="$tmp_root" CMOCKA_MESSAGE_OUTPUT=stdout "$prog" >"$log" 2>&1
  local rc=$?
  cat "$log"
  local p f
  p=$(sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' "$log" | tail -1)
  f=$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' "$log" | tail -1)
  p=${p:-0}; f=${f:-0}
  if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then f=1; fi   # crashed before its summary
  passed=$((passed + p)); failed=$((failed + f))
  [ "$f" -gt 0 ] && failed_names+=("$prog")
  echo "$((SECONDS - start)) $prog" >>"$timings"
}

# A script test's own NC_TMP (made) and interpreter, into script_dir and script_interpreter.
prepare_script() {
  script_dir="$tmp_root/$(basename "$1").d"
  mkdir -p "$script_dir"
  script_interpreter=bash
  case "$1" in *.py) script_interpreter=$PYTHON ;; esac
}

# Runs one script test; its exit status. The subshell becomes timeout(1), which runs the test
# in a process group of its own and passes a SIGTERM on to all of it.
exec_script() {
  prepare_script "$1"
  (cd "$root" && NC_TMP="$script_dir" exec timeout 1200 "$script_interpreter" "$1")
}

# Counts a finished script test: its exit status, seconds and name.
count_script() {
  local rc=$1 seconds=$2 script=$3
  if [ "$rc" -eq 0 ]; then passed=$((passed + 1)); echo "-- PASS $script"
  elif [ "$rc" -eq 77 ]; then skipped=$((skipped + 1)); echo "-- SKIP $script"
  else failed=$((failed + 1)); failed_names+=("$script"); echo "-- FAIL $script (exit $rc)"; fi
  echo "$seconds $script" >>"$timings"
}

run_script() {
  local script=$1 rc
  echo "== $script"
  local start=$SECONDS
  exec_script "$script"
  rc=$?
  count_script "$rc" "$((SECONDS - start))" "$script"
}

# Runs the given script tests up to max_jobs at a time. Each one's output is printed whole, in
# start order, once it and those started before it have ended. pool_running: the running tests'
# timeout(1) processes, which the INT/TERM trap stops.
pool_dir="$tmp_root/pool"
run_pool() {
  local max_jobs=$1
  shift
  local names=("$@") n=$# next=0 reported=0 running=0 pid rc k
  local -A index_of=()
  local -a rc_of=() start_of=() seconds_of=()
  mkdir -p "$pool_dir"
  while [ "$reported" -lt "$n" ]; do
    if [ "$next" -lt "$n" ] && [ "$running" -lt "$max_jobs" ]; then
      start_of[next]=$SECONDS
      prepare_script "${names[next]}"
      # the background job is timeout(1) itself: the trap's SIGTERM reaches the whole test
      (cd "$root" && NC_TMP="$script_dir" \
        exec timeout 1200 "$script_interpreter" "${names[next]}") >"$pool_dir/$next.log" 2>&1 &
      index_of[$!]=$next
      pool_running[$!]=1
      next=$((next + 1)); running=$((running + 1))
      continue
    fi
    wait -n -p pid
    rc=$?
    k=${index_of[$pid]}
    unset "pool_running[$pid]"
    rc_of[k]=$rc
    seconds_of[k]=$((SECONDS - start_of[k]))
    running=$((running - 1))
    while [ "$reported" -lt "$next" ] && [ -n "${rc_of[reported]:-}" ]; do
      echo "== ${names[reported]}"
      cat "$pool_dir/$reported.log"
      count_script "${rc_of[reported]}" "${seconds_of[reported]}" "${names[reported]}"
      reported=$((reported + 1))
    done
  done
}

while IFS= read -r prog; do
  [ -n "$filter" ] && [[ "$prog" != *"$filter"* ]] && continue
  run_cmocka "$prog"
done < <(find "$build_tests" -type f -name 'test_*' ! -name '*.o' ! -name '*.d' -perm -u+x 2>/dev/null | sort)

case_scripts=()
while IFS= read -r script; do
  [ -n "$filter" ] && [[ "$script" != *"$filter"* ]] && continue
  if [[ "$script" == tests/cases/* ]]; then case_scripts+=("$script"); continue; fi
  run_script "$script"
done < <(cd "$root" && find tests -type f \( -name 'test_*.sh' -o -name 'test_*.py' \) | sort)

if [ "$case_jobs" -gt 1 ]; then
  [ ${#case_scripts[@]} -gt 0 ] && run_pool "$case_jobs" "${case_scripts[@]}"
else
  for script in "${case_scripts[@]}"; do run_script "$script"; done
fi

echo
echo "slowest tests (seconds):"
sort -rn "$timings" | head -8 | sed 's/^/  /'
if [ ${#failed_names[@]} -gt 0 ]; then
  echo "failed: ${failed_names[*]}"
fi
if [ "$skipped" -gt 0 ]; then
  echo "$passed passed, $failed failed, $skipped skipped"
else
  echo "$passed passed, $failed failed"
fi
[ "$failed" -eq 0 ]
