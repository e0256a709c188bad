#!/usr/bin/env bash
# test_killed_output — fem_solver and dem_solver killed (SIGKILL) in the middle of a run: their
# result rows wait in memory between writes (nc_h5_flush_due), so what the kill leaves is the
# last write. The HDF5 file opens, every series is as long as the output times, and the XDMF
# file lists only complete output steps of it (tests/xdmf_check.py against the output times),
# more than the first. With sparse output, the FEM's monitor rows (every step) are written as
# they come too.
. tests/e2e_lib.sh

killed() {   # NAME OUTPUT_DIR XDMF TIMES_DATASET COMMAND...: runs COMMAND, kills it mid-run
  local name=$1 out=$2 xdmf=$3 times=$4
  shift 4
  "$@" --output "$out" > "$NC_TMP/$name.log" 2>&1 &
  local pid=$!
  # killed once a second write has listed its steps (the first comes at once), while it runs
  local grids=0
  for _ in $(seq 1 600); do
    grids=$(grep -c 'GridType="Uniform"' "$out/$xdmf" 2>/dev/null)
    [ "${grids:-0}" -ge 2 ] && break
    sleep 0.1
  done
  [ "${grids:-0}" -ge 2 ] || { cat "$NC_TMP/$name.log"; fail "$name: $xdmf lists ${grids:-no} steps after 60 s"; }
  kill -0 "$pid" 2>/dev/null || { cat "$NC_TMP/$name.log"; fail "$name: ended before it was killed"; }
  kill -KILL "$pid"
  wait "$pid" 2>/dev/null
  "$PY" tests/xdmf_check.py "$out/$xdmf" "$times" || fail "$name: $xdmf does not describe what was written"
  "$PY" - "$out" "$xdmf" "$times" <<'PY' || fail "$name: results not readable after SIGKILL"
import sys, h5py, xml.etree.ElementTree as ET
out, xdmf, times = sys.argv[1:]
h5 = out + "/" + ("fem.h5" if xdmf == "fem.xdmf" else "dem.h5")
series = {"fem.xdmf": ["/output/" + k for k in ("step", "load_factor", "displacement", "velocity",
                                                "position", "axial_force", "strain", "reaction")],
          "particles.xdmf": ["/particles/position", "/particles/velocity",
                             "/particles/angular_velocity", "/walls/force", "/energy/kinetic"]}[xdmf]
with h5py.File(h5, "r") as f:
    rows = f[times].shape[0]
    lengths = {name: f[name].shape[0] for name in series}
assert set(lengths.values()) == {rows}, (rows, lengths)
grids = len(ET.parse(out + "/" + xdmf).getroot().findall(".//Grid[@GridType='Uniform']"))
assert 2 <= grids <= rows, "%d grids listed, %d rows written" % (grids, rows)
print("%s: %d output rows written, %d listed in %s after SIGKILL" % (h5, rows, grids, xdmf))
PY
}

# FEM: the 21 x 21 net for 20 s instead of 1 (about 8 s)
"$PY" - "$NC_TMP/net.json" <<'PY'
import json, sys
m = json.load(open("fem_solver/examples/net_dynamic.json"))
m["analysis"]["end_time_s"] = 20.0
json.dump(m, open(sys.argv[1], "w"))
PY
killed fem "$NC_TMP/fem" fem.xdmf /output/time "$NC_BIN/fem_solver" "$NC_TMP/net.json"

# FEM with one output step in 200 s (minutes of wall time: it is killed long before): its
# monitor rows (every step) are written every fraction of a second too, not held until the
# next output step
"$PY" - "$NC_TMP/sparse.json" <<'PY'
import json, sys
m = json.load(open("fem_solver/examples/net_dynamic.json"))
m["analysis"]["end_time_s"] = 200.0
m["output"]["interval_steps"] = 100000
json.dump(m, open(sys.argv[1], "w"))
PY
"$NC_BIN/fem_solver" "$NC_TMP/sparse.json" --output "$NC_TMP/sparse" > "$NC_TMP/sparse.log" 2>&1 &
pid=$!
for _ in $(seq 1 100); do [ -f "$NC_TMP/sparse/fem.xdmf" ] && break; sleep 0.1; done
[ -f "$NC_TMP/sparse/fem.xdmf" ] || { cat "$NC_TMP/sparse.log"; fail "sparse output: no fem.xdmf after 10 s"; }
sleep 1.5
kill -0 "$pid" 2>/dev/null || { cat "$NC_TMP/sparse.log"; fail "sparse output: ended before it was killed"; }
kill -KILL "$pid"
wait "$pid" 2>/dev/null
"$PY" - "$NC_TMP/sparse/fem.h5" <<'PY' || fail "sparse output: monitor rows not written while running"
import sys, h5py
with h5py.File(sys.argv[1], "r") as f:
    rows = {k: f["/monitor/" + k].shape[0] for k in ("time", "displacement", "velocity")}
    assert len(set(rows.values())) == 1, rows
    assert rows["time"] >= 10, "only %d monitor rows after 1.5 s" % rows["time"]
    assert f["/output/time"].shape[0] == 1
print("%s: %d monitor rows written, 1 output step, after SIGKILL" % (sys.argv[1], rows["time"]))
PY

# DEM: spheres settling in a box (about 4 s)
killed dem "$NC_TMP/dem" particles.xdmf /time "$NC_BIN/dem_solver" dem_solver/examples/settle.json
echo PASS
