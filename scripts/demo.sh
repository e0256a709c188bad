#!/usr/bin/env bash
# `make demo`: runs the default case (cases/rest_position, strong coupling), plots it, writes
# its run report (scripts/report.py: OUT_DIR/report.md) and says where the results are.
# Usage: scripts/demo.sh [OUT_DIR]   (default results/demo)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/results/demo}
PYTHON=/usr/bin/python3
# paper 7.2 with strong coupling at the paper's largest step (3e-2 s) and a damped contact
# (COR 0.5), run long enough (8 s) for the sphere to come to rest on the cable
echo "demo: running cases/rest_position (paper 7.2, strong coupling, dt 3e-2 s, COR 0.5, 8 s) into $out"
echo "demo: (the paper's sphere has a density of 3.5e4 kg/m³, denser than any rock: the DEM warns about it, as it should)"
"$root/scripts/run_case.sh" "$root/cases/rest_position" --out "$out" \
  --set coupler.dt=3e-2 --set fem.analysis.dt_s=3e-2 \
  --set coupler.end_time=8 --set fem.analysis.end_time_s=8 \
  --set dem.materials.0.restitution=0.5
echo "demo: the FEM static solution for the same load (eq. (43)) into $out/static"
"${NC_BIN:-$root/bin}/fem_solver" "$root/cases/rest_position/static.json" --output "$out/static" >"$out/static.log" 2>&1 || {
  echo "demo: static solve failed, see $out/static.log" >&2; exit 1; }
"$PYTHON" "$root/scripts/plot_results.py" "$out" --node 1 --static "$out/static" >/dev/null
"$PYTHON" - "$out" "$root/scripts" <<'PY'
import sys
sys.path.insert(0, sys.argv[2])
import nc_results
out = sys.argv[1]
a = nc_results.load_monitor(out).node(1)
s = nc_results.load_monitor(out + "/static").node(1)[-1]
c = nc_results.load_coupling(out)
print("demo: Point A at the end %.5f m, static solution %.5f m (%.2f %% apart); peak %.4f m; "
      "%d steps, %.2f interface iterations per step"
      % (a[-1], s, 100 * abs(a[-1] - s) / abs(s), a.min(), len(c.iterations), c.iterations.mean()))
PY
"$PYTHON" "$root/scripts/report.py" "$out" >"$out/report.txt" 2>&1 || {
  cat "$out/report.txt" >&2; echo "demo: the run report failed" >&2; exit 1; }
echo "demo: run report $out/report.md"
grep '^verdict: ' "$out/report.txt" | sed 's/^/demo: /'
cat <<MSG

demo: done.
  results (HDF5):  $out/fem.h5  $out/dem.h5  $out/coupling.h5
  ParaView:        paraview $out/fem.xdmf $out/particles.xdmf
                   (net: colour by axial_force; rocks: Glyph filter, Sphere, scale array 'radius',
                   scale factor 2; the DEM's copy of the net is in $out/dem_net.xdmf)
  picture:         xvfb-run -a pvpython scripts/paraview_view.py $out   (writes $out/paraview.png)
  run report:      $out/report.md   (plots in $out/report/, summary in $out/report.txt)
  plots (PNG):     $(ls "$out"/plots/*.png | tr '\n' ' ')
  iterations log:  $out/iterations.log   (step time iterations converged residual)
MSG
