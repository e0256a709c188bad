#!/usr/bin/env bash
# test_disk_full — a full disk during a run (a small tmpfs as the output folder): fem_solver and
# dem_solver stop with exit 1 and a message naming the file and the operating system's reason
# ("No space left on device"), do not crash closing the HDF5 file, leave no temporary file, and
# what they wrote before stays readable: the HDF5 file opens, and its XDMF file lists only
# complete output steps (tests/xdmf_check.py against the HDF5 output times). Needs root (to
# mount the tmpfs); skipped otherwise.
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
assert n >= 2, "only %d complete output steps" % n
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
echo PASS
