#!/usr/bin/env bash
# netcouple-check (protocol/check/README.md) against the participants of this repository:
#  - fem_solver and dem_solver (the DEM on the FEM's own interface, saved by the FEM's check)
#    pass every row, with --strict (no warnings either);
#  - the Python participants spring_plate.py and ball_dem.py pass, also with --strict;
#  - spring_plate.py --no-restore fails, on the restore rows and on nothing else;
#  - a program that exits at once fails on the endpoint file, in bounded time.
# The JSON report (--json) is read back to check the rows, not only the exit status.
set -u
: "${NC_BIN:?}" "${NC_TMP:?}"
PY=${PYTHON:-/usr/bin/python3}
check=$NC_BIN/netcouple-check
[ -x "$check" ] || { echo "FAIL: $check not built"; exit 1; }
fail() { echo "FAIL: $*"; exit 1; }
cd "$NC_ROOT" || exit 1

cp tests/coupler/cases/small_net/fem.json "$NC_TMP/fem.json"
cp tests/coupler/cases/plate_ball/fem.json "$NC_TMP/plate.json"
# a rock and a ball pressed 1 mm into the plane z = 0 at the origin (the centre of the small
# net, and of the plate): the DEM's first answer is a non-zero force, so restore is tested
cat > "$NC_TMP/dem.json" <<'JSON'
{
  "description": "a 0.1 m rock (10.5 kg) 1 mm into the interface plane z = 0, moving down at 1 m/s",
  "materials": [{"name": "rock", "youngs_modulus_pa": 3e10, "poisson_ratio": 0.2,
                 "density_kg_m3": 2500, "restitution": 0.3, "friction": 0.5}],
  "particles": [{"position": [0.0, 0.0, 0.099], "radius": 0.1, "velocity": [0, 0, -1],
                 "material": "rock"}],
  "net_wall": {"youngs_modulus_pa": 1e11, "poisson_ratio": 0.3, "friction": 0.3},
  "gravity": [0, 0, -9.81],
  "end_time_s": 1.0,
  "output_interval_s": 0.01
}
JSON
cat > "$NC_TMP/ball.json" <<'JSON'
{"comment": "1 kg ball of radius 0.1 m pressed 1 mm into the plane z = 0",
 "radius": 0.1, "mass": 1.0, "position": [0.0, 0.0, 0.099], "stiffness": 100000.0,
 "damping_ratio": 0.3, "substeps": 10}
JSON

run() {   # name expected-status netcouple-check-args... -> output in $NC_TMP/name.out
  local name=$1 expected=$2; shift 2
  local t0=$SECONDS
  "$check" --work "$NC_TMP/$name" --json "$NC_TMP/$name.report.json" "$@" >"$NC_TMP/$name.out" 2>&1
  local rc=$?
  [ "$rc" -eq "$expected" ] || { cat "$NC_TMP/$name.out"; fail "$name: exit status $rc, expected $expected"; }
  echo "$name: exit $rc in $((SECONDS - t0)) s"
}

# rows NAME=VERDICT that must hold in report FILE; "FAIL-ONLY a,b" : the FAIL rows are exactly a, b
rows() {
  "$PY" - "$@" <<'PY'
import json, sys
path, wanted = sys.argv[1], sys.argv[2:]
with open(path) as f:
    report = json.load(f)
verdict = {c["name"]: c["verdict"] for c in report["checks"]}
bad = []
for w in wanted:
    if w.startswith("FAIL-ONLY="):
        expected = sorted(x for x in w[len("FAIL-ONLY="):].split(",") if x)
        got = sorted(n for n, v in verdict.items() if v == "FAIL")
        if got != expected:
            bad.append("FAIL rows %s, expected %s" % (got, expected))
        continue
    name, v = w.rsplit("=", 1)
    if verdict.get(name) != v:
        bad.append("%s: %s, expected %s" % (name, verdict.get(name), v))
if len(report["checks"]) < 25 and "endpoint file=FAIL" not in wanted:
    bad.append("only %d rows" % len(report["checks"]))
if bad:
    print("\n".join(c["verdict"] + "  " + c["name"] + "  " + c["detail"] for c in report["checks"]))
    sys.exit("; ".join(bad))
PY
}
must=("restore: solve repeated=PASS" "restore: step begun again=PASS" "exit status: clean run=PASS"
      "exit status: after errors=PASS" "idle timeout=PASS" "malformed: NaN in an array=PASS"
      "malformed: bad JSON=PASS" "hello: role=PASS" "FAIL-ONLY=")

# the C solvers: everything passes, no warnings
run fem 0 --strict --role fem --save-interface "$NC_TMP/net.json" -- "$NC_BIN/fem_solver" "$NC_TMP/fem.json"
rows "$NC_TMP/fem.report.json" "${must[@]}" "session: foreign command=PASS" \
  "order: solve before begin_step=PASS" || fail "fem_solver rows"
run dem 0 --strict --role dem --interface "$NC_TMP/net.json" -- "$NC_BIN/dem_solver" "$NC_TMP/dem.json"
rows "$NC_TMP/dem.report.json" "${must[@]}" "session: foreign command=PASS" \
  "interface=PASS" || fail "dem_solver rows"
grep -q "accepted the 49-node, 84-element interface" "$NC_TMP/dem.out" || fail "dem: not the FEM's interface"

# the Python participants: pass, also with --strict
run plate 0 -- "$PY" scripts/participants/spring_plate.py "$NC_TMP/plate.json"
rows "$NC_TMP/plate.report.json" "${must[@]}" "checkpoint/resume bit-identity=PASS" \
  || fail "spring_plate rows"
run ball 0 --no-idle-check -- "$PY" scripts/participants/ball_dem.py "$NC_TMP/ball.json"
rows "$NC_TMP/ball.report.json" "restore: solve repeated=PASS" "restore: step begun again=PASS" \
  "exit status: after errors=PASS" "hello: role=PASS" "FAIL-ONLY=" || fail "ball_dem rows"
grep -q "max |value| 10.1" "$NC_TMP/ball.out" || fail "ball: force not the ball's weight + contact: $(grep 'solve ' "$NC_TMP/ball.out")"
run ball_strict 0 --strict --no-idle-check -- "$PY" scripts/participants/ball_dem.py "$NC_TMP/ball.json"

# a participant that does not restore: caught, on the restore rows only
run no_restore 1 --no-idle-check -- "$PY" scripts/participants/spring_plate.py "$NC_TMP/plate.json" --no-restore
rows "$NC_TMP/no_restore.report.json" \
  "FAIL-ONLY=restore: solve repeated,restore: step begun again,next step" || fail "no-restore rows"
grep -q "does not restore its start-of-step state" "$NC_TMP/no_restore.out" || fail "no-restore message"

# a program that exits at once: the endpoint row fails, without waiting for the timeouts
t0=$SECONDS
run gone 1 --no-idle-check --start-timeout 30 -- /bin/sh -c 'echo "cannot read input" >&2; exit 3'
[ $((SECONDS - t0)) -lt 10 ] || fail "gone: took $((SECONDS - t0)) s"
rows "$NC_TMP/gone.report.json" "endpoint file=FAIL" || fail "gone rows"
grep -q "exited with status 3 .*cannot read input" "$NC_TMP/gone.out" || fail "gone: $(cat "$NC_TMP/gone.out")"
echo PASS
