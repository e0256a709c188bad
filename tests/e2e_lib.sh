# e2e_lib.sh — sourced by the end-to-end shell tests (tests/cases/, tests/coupler/) that run
# the three programs on a case: checks the environment the test runner gives them (NC_BIN,
# NC_TMP; the programs must be built, otherwise the test is skipped with exit 77), sets PY
# to the Python that has h5py/numpy, and defines fail and run_case.
set -u
: "${NC_BIN:?}" "${NC_TMP:?}"
PY=${PYTHON:-/usr/bin/python3}
for program in fem_solver dem_solver coupler; do
  [ -x "$NC_BIN/$program" ] || { echo "SKIP: $NC_BIN/$program not built"; exit 77; }
done

fail() { echo "FAIL: $*"; exit 1; }

# run_case NAME CASE_DIR [run_case.sh arguments ...]: runs the case into $NC_TMP/NAME (its
# console output in $NC_TMP/NAME.out); on failure shows the logs and fails the test.
run_case() {
  local name=$1 case_dir=$2
  shift 2
  scripts/run_case.sh "$case_dir" --out "$NC_TMP/$name" --quiet "$@" > "$NC_TMP/$name.out" 2>&1 \
    || { tail -n 20 "$NC_TMP/$name.out" "$NC_TMP/$name"/*.log; fail "$name: run_case.sh failed"; }
}

# expect_reliable NAME ...: each run's summary ends with "results are reliable".
expect_reliable() {
  local name
  for name in "$@"; do
    grep -v '^$' "$NC_TMP/$name/coupler.log" | tail -n 1 | grep -q "^coupler: results are reliable" \
      || fail "$name: not reliable: $(tail -n 1 "$NC_TMP/$name/coupler.log")"
  done
}

# The terrain cases (terrain_net, terrain_curtain) as scripts/study.py compliance runs them at
# rock–net restitution 0.3 and 5× their Δt (0.005 s) over 2.15 s, with the interface Jacobian
# and Aitken from the full step: --set options for run_case.
TERRAIN_5X=(--set coupler.interface_jacobian=true --set coupler.relaxation.method=aitken
            --set coupler.relaxation.alpha=1.0 --set coupler.relaxation.first_iteration_cap=1.0
            --set coupler.efficiency.far_step=true --set coupler.efficiency.far_step_factor=10
            --set coupler.dt=0.005 --set fem.analysis.dt_s=0.005
            --set coupler.end_time=2.15 --set fem.analysis.end_time_s=2.15
            --set dem.materials.0.restitution=0.3 --set dem.net_wall.restitution=0.3)
