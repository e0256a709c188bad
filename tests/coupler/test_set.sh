#!/usr/bin/env bash
# test_set — run_case.sh's --set overrides (netcouple-set): numbers, booleans, strings, JSON
# lists and objects land where the dotted path says (list indices also in brackets), in the
# three files; missing keys and objects are created, list items replaced; the result parses
# as the same JSON as the input with exactly those changes (compared with Python's json
# module). Every bad override (no '=', an unknown file, an index past the list, a path through
# a number, an empty name, brackets around anything but an index, a file that is not JSON)
# exits 2 with a message naming it, and leaves the files untouched. And
# through run_case.sh itself: the run uses the value set, a bad --set stops it before any
# program starts.
. tests/e2e_lib.sh
[ -x "$NC_BIN/netcouple-set" ] || { echo "SKIP: $NC_BIN/netcouple-set not built"; exit 77; }
dir="$NC_TMP/set"
rm -rf "$dir"; cp -R cases/rest_position "$dir"
cp -R cases/rest_position "$NC_TMP/set_before"

"$NC_BIN/netcouple-set" "$dir" coupler.scheme=weak coupler.dt=1e-3 \
  'dem.materials[0].restitution=0.2' dem.materials.0.name=granite coupler.relaxation.alpha=0.5 \
  coupler.new.deep.flag=true 'fem.analysis.note=two words' 'coupler.list=[1, 2.5, "a"]' \
  'dem.gravity.2=-9.80665' 'fem.extra={"a": {"b": null}}' || fail "valid overrides: exit $?"
"$PY" - "$NC_TMP/set_before" "$dir" <<'PY' || fail "the files are not the input with the overrides"
import json, sys
before, after = sys.argv[1], sys.argv[2]
def load(d, n):
    with open("%s/%s.json" % (d, n)) as f:
        return json.load(f)
c, d, f = (load(before, n) for n in ("coupler", "dem", "fem"))
c["scheme"] = "weak"; c["dt"] = 1e-3; c["relaxation"]["alpha"] = 0.5
c["new"] = {"deep": {"flag": True}}; c["list"] = [1, 2.5, "a"]
d["materials"][0]["restitution"] = 0.2; d["materials"][0]["name"] = "granite"
d["gravity"][2] = -9.80665
f["analysis"]["note"] = "two words"; f["extra"] = {"a": {"b": None}}
for name, want in (("coupler", c), ("dem", d), ("fem", f)):
    got = load(after, name)
    assert got == want, "%s.json: %r\n != %r" % (name, got, want)
    assert list(got) == list(want), "%s.json: key order changed" % name
print("overrides applied, nothing else changed")
PY
grep -q '^  "scheme": "weak",$' "$dir/coupler.json" || fail "coupler.json not indented by two spaces"

snapshot() { cat "$dir"/fem.json "$dir"/dem.json "$dir"/coupler.json | md5sum; }
refused() {   # EXPECTED_MESSAGE_PART OVERRIDE...
  local want=$1 before out rc
  shift
  before=$(snapshot)
  out=$("$NC_BIN/netcouple-set" "$dir" "$@" 2>&1); rc=$?
  [ "$rc" -eq 2 ] || fail "$*: exit $rc, expected 2 ($out)"
  [[ $out == *"$want"* ]] || fail "$*: message '$out' lacks '$want'"
  [ "$(snapshot)" = "$before" ] || fail "$*: files changed although refused"
  ! ls "$dir"/*.tmp >/dev/null 2>&1 || fail "$*: temporary file left"
}
refused "--set 'coupler': expected FILE.KEY=VALUE" coupler
refused "--set 'x=1': expected FILE.KEY=VALUE" x=1
refused "FILE must be fem, dem or coupler" foo.a=1
# the first override is valid: the second one's error leaves every file as it was
refused "'5' is not an index of a list of 1 item" coupler.dt=5 dem.materials.5.x=1
refused "'x' is not an index of a list of 1 item" dem.materials.x=1
refused "'x' is inside a number, not an object or list" coupler.dt.x=1
refused "an empty name in KEY" coupler..a=1
for bad in 'dem.materials[x].a=1' 'dem.materials[0]x=1' 'dem.materials[0.a=1' \
           'dem.materials]0.a=1' 'dem.materials[].a=1'; do
  refused "brackets in KEY hold a list index only" "$bad"
done
refused "'5' is not an index of a list of 1 item" 'dem.materials[5].x=1'
echo '{"broken": ' > "$dir/fem.json"
refused "$dir/fem.json:1:12: malformed JSON" fem.a=1
cp cases/rest_position/fem.json "$dir/fem.json"

# through the launcher
run_case set_run cases/rest_position --set coupler.end_time=0.2 --set fem.analysis.end_time_s=0.2 \
  --set 'dem.materials.0.restitution=0.4'
grep -q '"restitution": 0.4' "$NC_TMP/set_run/dem.json" || fail "run_case.sh: --set not applied"
"$PY" - "$NC_TMP/set_run/coupling.h5" <<'PY' || fail "run_case.sh: the run did not stop at the end_time set"
import h5py, sys
t = h5py.File(sys.argv[1], "r")["/steps/time"][-1]
assert abs(t - 0.2) < 1e-9, t
PY
out=$(scripts/run_case.sh cases/rest_position --out "$NC_TMP/set_bad" --set dem.materials.3.x=1 2>&1); rc=$?
[ "$rc" -eq 2 ] || fail "run_case.sh with a bad --set: exit $rc, expected 2"
[[ $out == *"'3' is not an index of a list of 1 item"* ]] || fail "run_case.sh bad --set: '$out'"
! ls "$NC_TMP/set_bad"/*.log >/dev/null 2>&1 || fail "run_case.sh started programs despite a bad --set"
echo PASS
