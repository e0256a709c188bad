#!/usr/bin/env bash
# Replays the seed corpus of every input reader's fuzz target (Gmsh, STL, fem.json, dem.json,
# coupler.json) once, through the replay programs of this build (built by `make tests`):
# under `make test SANITIZE=1` an out-of-bounds access or undefined behaviour fails the test.
set -u
cd "${NC_ROOT:-.}"
dir=$(cd "${NC_BUILD_TESTS:?}/../fuzz" && pwd) || exit 1
status=0
for pair in fem_solver:gmsh fem_solver:fem_json dem_solver:stl dem_solver:dem_json coupler:coupler_json; do
  module=${pair%%:*}; name=${pair#*:}
  prog="$dir/replay_$name"
  if [ ! -x "$prog" ]; then echo "missing $prog (run make tests)"; status=1; continue; fi
  echo "== $name"
  (cd "$module/fuzz/corpus_$name" && "$prog" .) || { echo "replay of $name failed"; status=1; }
done
exit $status
