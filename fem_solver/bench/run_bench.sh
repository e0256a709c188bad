#!/usr/bin/env bash
# run_bench.sh FEM_BENCH BARRIER_FEM_JSON — the FEM benchmark of `make bench` (target bench-fem).
#
# 1. fem_bench: the square cable nets 41x41, 81x81 and 161x161 (static Newton under a 2 kN
#    centre load, 200 dynamic steps) and 200 steps of the barrier in BARRIER_FEM_JSON;
# 2. the same static solves in CalculiX (Debian package `calculix-ccx`), when it is installed:
#    the net written by `fem_bench --write-calculix` (each cable an axial spring with the
#    cable's force law as its force–elongation table, fem_bench.c), both programs on all
#    cores. Printed: wall times (netcouple: set-up + solve in-process; CalculiX: its "Total
#    CalculiX Time", input to output), their ratio, and the centre deflections, which must
#    agree within 1e-4 (the table's interpolation and CalculiX's load stepping: measured
#    2.2e-5 to 6.0e-5).
set -eu
exe=${1:?usage: run_bench.sh path/to/fem_bench path/to/barrier/fem.json}
barrier=${2:?usage: run_bench.sh path/to/fem_bench path/to/barrier/fem.json}
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
"$exe" "$barrier"

echo "== CalculiX, the same static solves (each program on $(nproc) threads)"
if ! command -v ccx >/dev/null 2>&1; then
  echo "ccx not installed (apt-get install calculix-ccx): comparison skipped"
  exit 0
fi
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fem-bench.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
status=0
printf '%9s | %12s %6s | %12s %6s | %7s | %12s %12s %9s\n' net "netcouple_s" iters \
  "calculix_s" iters ratio "w_netcouple" "w_calculix" rel_diff
for n in 41 81 161; do
  ours=$("$exe" --static "$n") || { echo "fem_bench --static $n failed"; exit 1; }
  read -r _ _ setup_s solve_s iters w_ours _ <<<"$ours"
  "$exe" --write-calculix "$n" "$tmp/net$n.inp" || { echo "fem_bench --write-calculix $n failed"; exit 1; }
  if ! (cd "$tmp" && OMP_NUM_THREADS=$(nproc) ccx -i "net$n" >"net$n.log" 2>&1); then
    echo "ccx failed on the ${n}x$n net:"; tail -20 "$tmp/net$n.log"; exit 1
  fi
  ccx_s=$(sed -n 's/^Total CalculiX Time: *//p' "$tmp/net$n.log")
  [ -n "$ccx_s" ] || { echo "ccx: no 'Total CalculiX Time' in its log (${n}x$n)"; exit 1; }
  ccx_iters=$(grep -c '^ iteration' "$tmp/net$n.log" || true)
  # the centre node's last displacement line: node, ux, uy, uz
  w_ccx=$(awk 'NF == 4 && $1 ~ /^[0-9]+$/ { w = -$4 } END { print w }' "$tmp/net$n.dat")
  line=$(awk -v n="$n" -v s="$setup_s" -v t="$solve_s" -v i="$iters" -v c="$ccx_s" -v ci="$ccx_iters" \
             -v w="$w_ours" -v wc="$w_ccx" 'BEGIN {
    ours = s + t; d = (wc - w) / w; a = d < 0 ? -d : d
    printf "%4dx%-4d | %12.3f %6d | %12.3f %6d | %7.1f | %12.7f %12.7f %9.1e %s\n", n, n, ours, i,
           c, ci, c / ours, w, wc, d, a <= 1e-4 ? "" : "(agreement 1e-4 MISSED)" }')
  echo "$line"
  case $line in *MISSED*) status=1 ;; esac
done
echo "iters: Newton iterations (CalculiX: over its load increments, from a tenth of the load;"
echo "from the full load its Newton iteration diverges); ratio: CalculiX time / netcouple time"
exit $status
