#!/usr/bin/env bash
# `make demo`: runs the default case (cases/rest_position, strong coupling), plots it and
# says where the results are. Usage: scripts/demo.sh [OUT_DIR]   (default results/demo)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/results/demo}
PYTHON=/usr/bin/python3
echo "demo: running cases/rest_position (paper 7.2, strong coupling) into $out"
"$root/scripts/run_case.sh" "$root/cases/rest_position" --out "$out"
echo "demo: the FEM static solution for the same load (eq. 43) into $out/static"
"${NC_BIN:-$root/bin}/fem_solver" "$root/cases/rest_position/static.json" --output "$out/static" >"$out/static.log" 2>&1 || {
  echo "demo: static solve failed, see $out/static.log" >&2; exit 1; }
"$PYTHON" "$root/scripts/plot_results.py" "$out" --node 1 --static "$out/static" >/dev/null
cat <<MSG

demo: done.
  results (HDF5):  $out/fem.h5  $out/dem.h5  $out/coupling.h5
  ParaView:        paraview $out/fem.xdmf $out/dem.xdmf
                   (net: colour by axial_force; spheres: Glyph filter, Sphere, scale by 'radius' x2)
  plots (PNG):     $(ls "$out"/plots/*.png | tr '\n' ' ')
  iterations log:  $out/iterations.log   (step time iterations converged residual)
MSG
