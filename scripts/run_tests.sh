#!/usr/bin/env bash
# Runs every netcouple test and ends with one line "N passed, N failed".
#   scripts/run_tests.sh BUILD_TEST_DIR BIN_DIR [FILTER]
# - compiled cmocka programs: BUILD_TEST_DIR/<module>/test_*   (each cmocka test counts)
# - script tests: tests/<module>/test_*.sh and tests/<module>/test_*.py (each file counts once;
#   exit 0 = pass, 77 = skipped). They get NC_BIN (programs), NC_BUILD_TESTS and NC_TMP.
# FILTER (optional) is a substring a test path must contain.
# The case tests (tests/cases/: whole coupled runs, most of the suite's time) run NC_TEST_JOBS
# at a time (default: the number of cores), after every other test has run alone: those time
# replies, stalls and signals and must not share the machine.
set -u
build_tests=${1:?build test dir}
bin_dir=${2:?bin dir}
filter=${3:-${TEST_FILTER:-}}
root=$(cd "$(dirname "$0")/.." && pwd)
PYTHON=/usr/bin/python3   # Debian's interpreter, which has python3-zmq/h5py/numpy
mkdir -p "$bin_dir"
export NC_BIN=$(cd "$bin_dir" && pwd)
export NC_BUILD_TESTS=$(cd "$build_tests" 2>/dev/null && pwd || echo "$build_tests")
export NC_ROOT=$root
export PYTHON
tmp_root=$(mktemp -d "${TMPDIR:-/tmp}/netcouple-tests.XXXXXX")
trap 'rm -rf "$tmp_root"' EXIT
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

# Runs one script test in its own NC_TMP; its exit status.
exec_script() {
  local script=$1 dir="$tmp_root/$(basename "$script").d"
  mkdir -p "$dir"
  case "$script" in
    *.py) (cd "$root" && NC_TMP="$dir" timeout 1200 "$PYTHON" "$script") ;;
    *)    (cd "$root" && NC_TMP="$dir" timeout 1200 bash "$script") ;;
  esac
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

# Runs the given script tests up to max_jobs at a time, each one's output whole when it ends.
pool_dir="$tmp_root/pool"
pool_reported=0
report_finished() {
  local k
  for ((k = pool_reported; k < pool_started; k++)); do
    [ -f "$pool_dir/$k.rc" ] || break   # in start order, so the output keeps that order
    echo "== ${pool_names[$k]}"
    cat "$pool_dir/$k.log"
    count_script "$(cat "$pool_dir/$k.rc")" "$(cat "$pool_dir/$k.seconds")" "${pool_names[$k]}"
    pool_reported=$((k + 1))
  done
}
run_pool() {
  local max_jobs=$1 script running=0
  shift
  mkdir -p "$pool_dir"
  pool_names=("$@")
  pool_started=0
  for script in "$@"; do
    if [ "$running" -ge "$max_jobs" ]; then
      wait -n
      running=$((running - 1))
      report_finished
    fi
    (
      start=$SECONDS
      exec_script "$script" >"$pool_dir/$pool_started.log" 2>&1
      rc=$?
      echo "$((SECONDS - start))" >"$pool_dir/$pool_started.seconds"
      echo "$rc" >"$pool_dir/$pool_started.rc"
    ) &
    pool_started=$((pool_started + 1))
    running=$((running + 1))
  done
  wait
  report_finished
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

case_jobs=${NC_TEST_JOBS:-$(nproc 2>/dev/null || echo 1)}
[[ $case_jobs =~ ^[1-9][0-9]*$ ]] || { echo "NC_TEST_JOBS: expected a count >= 1, got '$case_jobs'"; exit 2; }
[ ${#case_scripts[@]} -gt 0 ] && run_pool "$case_jobs" "${case_scripts[@]}"

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
