#!/usr/bin/env bash
# run_bench.sh DEM_BENCH — the DEM benchmark of `make bench` (target bench-dem).
#
# 1. granular settle of 20,000 spheres (Hertz–Mindlin, friction) for a fixed number of steps,
#    particle-steps per second on 1 and 2 threads;
# 2. cost growth from 5,000 to 80,000 spheres (1 thread; DEM_BENCH_LARGE=1 adds 160k, 320k);
# 3. the same 20,000-sphere settle in LIGGGHTS (Debian package `liggghts`), same initial state,
#    material, walls and time step, 1 process, when it is installed.
# Environment: DEM_BENCH_STEPS (default 1500), DEM_BENCH_SCALE_STEPS (default 1000).
set -eu
exe=${1:?usage: run_bench.sh path/to/dem_bench}
here=$(cd "$(dirname "$0")" && pwd)
steps=${DEM_BENCH_STEPS:-1500}
scale_steps=${DEM_BENCH_SCALE_STEPS:-1000}
# Passive waiting keeps a 2-thread team usable when other processes share the cores (spinning
# threads then wait a scheduler slice at every barrier); set OMP_WAIT_POLICY=active to override.
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/dem-bench.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

echo "== DEM granular settle, 20000 spheres, $steps steps of 5e-5 s"
for t in 1 2; do "$exe" 20000 "$steps" --threads "$t"; done

echo "== DEM scaling, 1 thread, $scale_steps steps (cost per particle-step should stay flat)"
sizes="5000 10000 20000 40000 80000"
[ "${DEM_BENCH_LARGE:-0}" = 1 ] && sizes="$sizes 160000 320000"
for n in $sizes; do "$exe" "$n" "$scale_steps" --threads 1; done

echo "== LIGGGHTS, same settle (20000 spheres, $steps steps, 1 process)"
if command -v liggghts >/dev/null 2>&1; then
  box=$("$exe" 20000 1 --threads 1 --write-liggghts "$tmp/settle.data" | sed -n 's/^box //p')
  (cd "$tmp" && liggghts -in "$here/in.settle" -var data "$tmp/settle.data" -var box "$box" \
     -var steps "$steps" -log none -echo none >"$tmp/liggghts.out" 2>&1) || {
    echo "liggghts failed:"; tail -20 "$tmp/liggghts.out"; exit 1; }
  awk '/^Loop time of/ { t = $4; n = $9; a = $12;
         printf "liggghts: %d spheres, %d steps, 1 process: %.3f s, %.3e particle-steps/s\n", a, n, t, a * n / t }' \
    "$tmp/liggghts.out"
  grep -E "^ +$steps +" "$tmp/liggghts.out" | awk '{ printf "liggghts: kinetic energy at the end %.4g J\n", $3 }'
else
  echo "liggghts not installed (apt-get install liggghts): comparison skipped"
fi
