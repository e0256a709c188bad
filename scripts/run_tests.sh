#!/usr/bin/env bash
# Runs every netcouple test and ends with one line "N passed, N failed".
#   scripts/run_tests.sh BUILD_TEST_DIR BIN_DIR [FILTER]
# - compiled cmocka programs: BUILD_TEST_DIR/<module>/test_*   (each cmocka test counts)
# - script tests: tests/<module>/test_*.sh and tests/<module>/test_*.py (each file counts once;
#   exit 0 = pass, 77 = skipped). They get NC_BIN (programs), NC_BUILD_TESTS and NC_TMP.
# FILTER (optional) is a substring a test path must contain.
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

run_script() {
  local script=$1 rc
  echo "== $script"
  local start=$SECONDS
  local dir="$tmp_root/$(basename "$script").d"
  mkdir -p "$dir"
  case "$script" in
    *.py) (cd "$root" && NC_TMP="$dir" timeout 1200 "$PYTHON" "$script") ;;
    *)    (cd "$root" && NC_TMP="$dir" timeout 1200 bash "$script") ;;
  esac
  rc=$?
  if [ $rc -eq 0 ]; then passed=$((passed + 1)); echo "-- PASS $script"
  elif [ $rc -eq 77 ]; then skipped=$((skipped + 1)); echo "-- SKIP $script"
  else failed=$((failed + 1)); failed_names+=("$script"); echo "-- FAIL $script (exit $rc)"; fi
  echo "$((SECONDS - start)) $script" >>"$timings"
}

while IFS= read -r prog; do
  [ -n "$filter" ] && [[ "$prog" != *"$filter"* ]] && continue
  run_cmocka "$prog"
done < <(find "$build_tests" -type f -name 'test_*' ! -name '*.o' ! -name '*.d' -perm -u+x 2>/dev/null | sort)

while IFS= read -r script; do
  [ -n "$filter" ] && [[ "$script" != *"$filter"* ]] && continue
  run_script "$script"
done < <(cd "$root" && find tests -type f \( -name 'test_*.sh' -o -name 'test_*.py' \) | sort)

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
