#!/usr/bin/env bash
# run_variant.sh NAME [--set ...] — runs cases/rest_position with overrides into
# ${OUT_ROOT:-/tmp/rp_runs}/NAME and prints the one-line verdict of summarize_run.py.
# Programs from $NC_BIN (default <repo>/bin); case from $CASE (default <repo>/cases/rest_position).
root=$(cd "$(dirname "$0")/../.." && pwd)
name=$1; shift
out=${OUT_ROOT:-/tmp/rp_runs}/$name
rm -rf "$out"; mkdir -p "$(dirname "$out")"
"$root/scripts/run_case.sh" "${CASE:-$root/cases/rest_position}" --out "$out" --quiet "$@" >/dev/null 2>"$out.err" \
  || { echo "$name: run failed: $(tail -2 "$out.err")"; }
[ -f "$out/fem.h5" ] || exit 1
echo "== $name $*"
/usr/bin/python3 "$root/scripts/diagnostics/summarize_run.py" "$out" --every 1000 | grep -v "^ *[0-9t]"
grep -h "steps.*iterations" "$out/coupler.log" | tail -1
