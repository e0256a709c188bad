#!/usr/bin/env bash
# test_disk_full — a full disk during a run (a small tmpfs as the output folder): fem_solver and
# dem_solver stop with exit 1 and a message naming the file and the operating system's reason
# ("No space left on device"), do not crash closing the HDF5 file, leave no temporary file, and
# what they wrote before stays readable: the HDF5 file opens, and its XDMF file lists only
# complete output steps (tests/xdmf_check.py against the HDF5 output times), at least the first
# (written at once; later rows wait in memory for a fraction of a second, nc_h5_flush_due, so
# a disk that fills within that time takes them with it). A coupled run
# whose coupling.h5 and fem.h5 (its monitor rows, every step) fill the disk together: exit 1,
# the reason said (by the coupler, or by run_case.sh when the full disk took the coupler's log
# too), coupling.h5 readable with the steps written, every series as long, and fem.h5 and
# dem.h5 readable too (a flush that failed part way once left a file unreadable, "addr
# overflow": nc_h5 takes the disk space before it writes). Needs root (to mount the tmpfs);
# skipped otherwise.
. tests/e2e_lib.sh
[ "$(id -u)" -eq 0 ] || { echo "SKIP: needs root to mount a small tmpfs"; exit 77; }
mnt="$NC_TMP/full"
mkdir -p "$mnt"
mount -t tmpfs -o size=2500k tmpfs "$mnt" 2>/dev/null || { echo "SKIP: cannot mount a tmpfs here"; exit 77; }
trap 'umount "$mnt" 2>/dev/null' EXIT

check() {   # program output_dir log xdmf times_dataset
  local rc=$1 out=$2 log=$3 xdmf=$4 times=$5
  [ "$rc" -eq 1 ] || { cat "$log"; fail "$out: expected exit 1 on a full disk, got $rc"; }
  grep -q "$out/[a-z_]*\.\(h5\|xdmf\).*No space left on device" "$log" \
    || { cat "$log"; fail "$out: no message naming the file and 'No space left on device'"; }
  ! ls "$out"/*.tmp >/dev/null 2>&1 || fail "$out: temporary file left: $(ls "$out"/*.tmp)"
  "$PY" tests/xdmf_check.py "$out/$xdmf" "$times" || fail "$out/$xdmf does not describe what was written"
  "$PY" - "$out/$xdmf" <<'PY' || fail "$out: nothing readable"
import sys, xml.etree.ElementTree as ET
n = len(ET.parse(sys.argv[1]).getroot().findall(".//Grid[@GridType='Uniform']"))
assert n >= 1, "no complete output step"
print("%s: %d complete output steps readable after the disk filled up" % (sys.argv[1], n))
PY
}

# FEM: the 21 x 21 net, 51 output steps of 40 kB (3.7 MB) into 2.5 MB
"$NC_BIN/fem_solver" fem_solver/examples/net_dynamic.json --output "$mnt/fem" > "$NC_TMP/fem.log" 2>&1
check $? "$mnt/fem" "$NC_TMP/fem.log" fem.xdmf /output/time

# DEM: 600 free-falling spheres, 51 output steps of 43 kB (2.2 MB) into 1 MB
umount "$mnt"
mount -t tmpfs -o size=1m tmpfs "$mnt" || fail "cannot mount the second tmpfs"
"$PY" - "$NC_TMP/rain.json" <<'PY'
import json, sys
spheres = [{"position": [0.3 * i, 0.3 * j, 1.0 + 0.3 * k], "radius": 0.1, "material": "rock"}
           for i in range(10) for j in range(10) for k in range(6)]
json.dump({"materials": [{"name": "rock", "youngs_modulus_pa": 3e10, "poisson_ratio": 0.2,
                          "density_kg_m3": 2650, "restitution": 0.3, "friction": 0.5}],
           "particles": spheres, "gravity": [0, 0, -9.81], "dt_s": "auto",
           "end_time_s": 0.1, "output_interval_s": 0.002}, open(sys.argv[1], "w"))
PY
"$NC_BIN/dem_solver" "$NC_TMP/rain.json" --output "$mnt/dem" > "$NC_TMP/dem.log" 2>&1
check $? "$mnt/dem" "$NC_TMP/dem.log" particles.xdmf /time

# coupled: rest_position, weak at 1e-3 s, the solvers' outputs small and written once; the
# tmpfs holds what a run of 0.01 s leaves plus 400 kB, which coupling.h5 fills within ~0.3 s
umount "$mnt"
coupled=(--quiet --set coupler.scheme=weak --set coupler.dt=1e-3 --set fem.analysis.dt_s=1e-3
         --set fem.output.interval_steps=100000 --set dem.output_interval_s=100)
scripts/run_case.sh cases/rest_position --out "$NC_TMP/probe" "${coupled[@]}" \
  --set coupler.end_time=0.01 --set fem.analysis.end_time_s=0.01 > "$NC_TMP/probe.out" 2>&1 \
  || { cat "$NC_TMP/probe.out"; fail "the probe run failed"; }
size_k=$(( $(du -sk "$NC_TMP/probe" | cut -f1) + 400 ))
mount -t tmpfs -o size=${size_k}k tmpfs "$mnt" || fail "cannot mount the third tmpfs"
scripts/run_case.sh cases/rest_position --out "$mnt/run" "${coupled[@]}" \
  --set coupler.end_time=20 --set fem.analysis.end_time_s=20 > "$NC_TMP/run.out" 2>&1
rc=$?
[ "$rc" -eq 1 ] || { cat "$NC_TMP/run.out"; fail "coupled run on a full disk: exit $rc, expected 1"; }
cat "$NC_TMP/run.out" "$mnt/run/coupler.log" | grep -Eq "No space left on device|messages could not be written .*a full disk" \
  || { cat "$NC_TMP/run.out" "$mnt/run/coupler.log"; fail "coupled run: the full disk is not said"; }
"$PY" - "$mnt/run/coupling.h5" <<'PY' || fail "coupling.h5 not readable after the disk filled up"
import sys, h5py
with h5py.File(sys.argv[1], "r") as f:
    n = f["/steps/time"].shape[0]
    lengths = {k: f[g][k].shape[0] for g in ("/steps", "/energy") for k in f[g]}
    assert n >= 10, "only %d steps" % n
    assert set(lengths.values()) == {n}, lengths
    assert f["/iterations/step"].shape[0] >= n
print("coupling.h5: %d steps readable after the disk filled up" % n)
PY
"$PY" - "$mnt/run/fem.h5" "$mnt/run/dem.h5" <<'PY' || fail "fem.h5 or dem.h5 not readable after the disk filled up"
import sys, h5py
with h5py.File(sys.argv[1], "r") as f:
    rows = {k: f["/monitor/" + k].shape[0] for k in ("time", "displacement", "velocity")}
    assert len(set(rows.values())) == 1, rows
    assert f["/output/time"].shape[0] >= 1
with h5py.File(sys.argv[2], "r") as f:
    assert f["/time"].shape[0] >= 1
print("fem.h5: %d monitor rows, dem.h5 readable after the disk filled up" % rows["time"])
PY
echo PASS
