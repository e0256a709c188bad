#!/usr/bin/env bash
# The coupler with two Python participants (scripts/participants: a rigid plate on a spring
# as the FEM, a ball with a linear contact as the DEM), started by scripts/run_case.sh.
# Checks against the analytic answer: the ball comes to rest on the plate, whose static
# deflection is w = -m g / k = -9.81e-3 m (1 kg, 1000 N/m); tolerance 1 % (the 30 % damped
# system has settled to < 0.1 % after 1.5 s). Also checks the history file layout and that
# weak, strong with Aitken on u/u̇ and strong with IQN-ILS on forces all run, and that both
# participants speak protocol version 2 with the coupler; a misspelt key stops at the input
# check (exit 2); a participant command with a quoted path holding a space runs.
set -u
: "${NC_BIN:?}" "${NC_TMP:?}"
PY=${PYTHON:-/usr/bin/python3}
case_dir=tests/coupler/cases/plate_ball
participants=(--fem-program "$PY scripts/participants/spring_plate.py"
              --dem-program "$PY scripts/participants/ball_dem.py")
fail() { echo "FAIL: $*"; exit 1; }

check() {   # dir scheme
  "$PY" - "$1" "$2" <<'PY' || exit 1
import sys, h5py, numpy as np
d, scheme = sys.argv[1], sys.argv[2]
with h5py.File(d + "/coupling.h5", "r") as f:
    names = ["/steps/time", "/steps/dt", "/steps/iterations", "/steps/residual",
             "/steps/converged", "/steps/contact_force", "/steps/in_contact",
             "/iterations/step", "/iterations/iteration", "/iterations/residual",
             "/iterations/alpha", "/iterations/contact_force"]
    for n in names:
        assert n in f, "missing dataset " + n
    steps = f["/steps/time"].shape[0]
    assert steps == 750, steps
    assert f["/steps/contact_force"].shape == (steps, 3)
    assert f["/iterations/contact_force"].shape[1] == 3
    assert f["/iterations/step"].shape[0] == f["/steps/iterations"][:].sum()
    assert abs(f["/steps/time"][-1] - 1.5) < 1e-12
    fz = f["/steps/contact_force"][-1, 2]
    # the ball rests: the net force on the plate is its weight, -9.81 N (1 %)
    assert abs(fz + 9.81) < 0.0981, fz
    assert f["/steps/in_contact"][-1] == 1
    if scheme == "strong":
        assert f["/steps/converged"][:].all()
plate = np.loadtxt(d + "/plate.csv", delimiter=",", skiprows=1)
w = plate[-1, 1]
expected = -1.0 * 9.81 / 1000.0
assert abs(w - expected) < 0.01 * abs(expected), (w, expected)
rows = [l for l in open(d + "/iterations.log") if not l.startswith("#")]
assert len(rows) == 750, len(rows)
print("%s: w = %.6e m (analytic %.6e), final contact force %.4f N" % (d, w, expected, fz))
PY
}

run() {   # name, extra args
  local name=$1; shift
  scripts/run_case.sh "$case_dir" --out "$NC_TMP/$name" --quiet "${participants[@]}" "$@" \
    || fail "$name: run_case.sh failed: $(cat "$NC_TMP/$name/coupler.log")"
}

run strong_aitken
check "$NC_TMP/strong_aitken" strong
run weak --set coupler.scheme=weak
check "$NC_TMP/weak" weak
run iqn_force --set coupler.relaxation.method=iqn-ils --set coupler.relaxed_quantity=force
check "$NC_TMP/iqn_force" strong
grep -q '"method": "iqn-ils"' "$NC_TMP/iqn_force/coupler.json" || fail "--set not applied"

# both Python participants speak protocol version 2 (the coupler's start line, not --quiet)
scripts/run_case.sh "$case_dir" --out "$NC_TMP/version" "${participants[@]}" \
  --set coupler.end_time=0.02 >/dev/null 2>&1 || fail "version run: $(cat "$NC_TMP/version/coupler.log")"
grep -Eq "fem = netcouple spring_plate.py \(tcp://[^,]*, protocol 2\), dem = netcouple ball_dem.py \(tcp://[^,]*, protocol 2\)" \
  "$NC_TMP/version/coupler.log" || fail "not protocol 2: $(head -n 2 "$NC_TMP/version/coupler.log")"

# a bad --set is refused with a message naming it
out=$(scripts/run_case.sh "$case_dir" --out "$NC_TMP/bad" "${participants[@]}" \
      --set dem.position.7=1 2>&1) && fail "bad --set accepted"
echo "$out" | grep -q "not an index" || fail "unclear --set message: $out"
# a typo in coupler.json is refused naming file and key
out=$(scripts/run_case.sh "$case_dir" --out "$NC_TMP/typo" "${participants[@]}" \
      --set coupler.tolerence=1e-3 2>&1); rc=$?
[ $rc -eq 2 ] || fail "typo: exit $rc, expected 2 (the input check before the start): $out"
grep -q "coupler.json: tolerence: unknown key" <<< "$out" || fail "typo message: $out"
# a participant command whose script lies in a folder with a space in its name, quoted as in
# a shell; run_case.programs keeps it in words a --resume reads back the same way
spaced="$NC_TMP/my participants"
mkdir -p "$spaced" && cp scripts/participants/*.py "$spaced"/
out=$(scripts/run_case.sh "$case_dir" --out "$NC_TMP/spaced" --quiet --set coupler.end_time=0.05 \
      --fem-program "$PY '$spaced/spring_plate.py'" --dem-program "$PY \"$spaced/ball_dem.py\"" 2>&1) \
  || fail "a quoted program path with a space: $out"
grep -qF "fem $PY ${spaced// /\\ }/spring_plate.py" "$NC_TMP/spaced/run_case.programs" \
  || fail "run_case.programs: $(cat "$NC_TMP/spaced/run_case.programs")"
out=$(scripts/run_case.sh "$case_dir" --out "$NC_TMP/unbalanced" --fem-program "$PY '$spaced/x.py" 2>&1)
[ $? -eq 2 ] && grep -q "cannot split the command" <<< "$out" || fail "an unbalanced quote: $out"
echo "PASS"
