#!/usr/bin/env bash
# run_variant.sh NAME [--set FILE.KEY=VALUE ...] — one run of a case with overrides into
# $OUT_ROOT/NAME (default results/variants/NAME) and the verdict lines of summarize_run.py
# (peak, rest, energy, iterations) plus the coupler's iteration count.
#   CASE     the case folder (default cases/rest_position; summarize_run.py expects a
#            rest_position-like case: monitor node 0 = Point A, particle 0 = the sphere)
#   NC_BIN   the programs (default <repo>/bin, as for scripts/run_case.sh)
#   OUT_ROOT where the run folders go
# Example: scripts/analysis/run_variant.sh cor05 --set dem.materials.0.restitution=0.5
root=$(cd "$(dirname "$0")/../.." && pwd)
name=${1:?usage: run_variant.sh NAME [--set FILE.KEY=VALUE ...]}; shift
out=${OUT_ROOT:-$root/results/variants}/$name
rm -rf "$out"; mkdir -p "$(dirname "$out")"
"$root/scripts/run_case.sh" "${CASE:-$root/cases/rest_position}" --out "$out" --quiet "$@" >/dev/null 2>"$out.err" \
  || { echo "$name: run failed: $(tail -2 "$out.err")"; }
[ -f "$out/fem.h5" ] || exit 1
echo "== $name $*"
/usr/bin/python3 "$root/scripts/analysis/summarize_run.py" "$out" --every 1000 | grep -v "^ *[0-9t]"
grep -h "steps.*iterations" "$out/coupler.log" | tail -1
