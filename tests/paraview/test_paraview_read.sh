#!/usr/bin/env bash
# test_paraview_read — every XDMF file the programs write opens in ParaView with ParaView's own
# choice of reader (OpenDataFile in pvpython, under xvfb-run): a standalone FEM run (fem.xdmf),
# a standalone DEM run (particles.xdmf) and a coupled run (fem.xdmf, particles.xdmf,
# dem_net.xdmf). Checked against the HDF5 output: point and cell counts, array names, every
# time value and the z range of the last step. Skipped (exit 77) where pvpython or xvfb-run is
# missing (Debian: apt-get install python3-paraview xvfb; .ci/run installs them).
. tests/e2e_lib.sh
for tool in pvpython xvfb-run; do
  command -v "$tool" >/dev/null || { echo "SKIP: $tool not installed (apt-get install python3-paraview xvfb)"; exit 77; }
done
out=$NC_TMP
"$NC_BIN/fem_solver" fem_solver/examples/net_dynamic.json --output "$out/fem" > "$out/fem.log" 2>&1 \
  || { cat "$out/fem.log"; fail "fem_solver"; }
"$NC_BIN/dem_solver" dem_solver/examples/drop.json --output "$out/dem" > "$out/dem.log" 2>&1 \
  || { cat "$out/dem.log"; fail "dem_solver"; }
run_case coupled tests/coupler/cases/small_net

# what ParaView must find, from the HDF5 files (h5py, Debian's python3)
"$PY" - "$out" > "$out/spec.json" <<'PY' || fail "reading the HDF5 output"
import json, sys, h5py
out = sys.argv[1]
spec = []
def fem(d):
    with h5py.File(d + "/fem.h5", "r") as f:
        z = f["/output/position"][-1, :, 2]
        spec.append(dict(file=d + "/fem.xdmf", points=f["/mesh/coordinates"].shape[0],
                         cells=f["/mesh/elements"].shape[0], point_arrays=["displacement", "velocity"],
                         cell_arrays=["axial_force", "strain"], times=f["/output/time"][:].tolist(),
                         z_last=[float(z.min()), float(z.max())]))
def particles(d):
    with h5py.File(d + "/dem.h5", "r") as f:
        z = f["/particles/position"][-1, :, 2]
        n = f["/particles/radius"].shape[0]
        spec.append(dict(file=d + "/particles.xdmf", points=n, cells=n,
                         point_arrays=["angular_velocity", "id", "radius", "velocity"], cell_arrays=[],
                         times=f["/time"][:].tolist(), z_last=[float(z.min()), float(z.max())]))
def net(d):
    with h5py.File(d + "/dem.h5", "r") as f:
        first = int(f["/net"].attrs["first_output_step"])
        z = f["/net/position"][-1, :, 2]
        spec.append(dict(file=d + "/dem_net.xdmf", points=f["/net/node_ids"].shape[0],
                         cells=f["/net/edges"].shape[0], point_arrays=["contact_force"], cell_arrays=[],
                         times=f["/time"][first:].tolist(), z_last=[float(z.min()), float(z.max())]))
fem(out + "/fem"); particles(out + "/dem")
fem(out + "/coupled"); particles(out + "/coupled"); net(out + "/coupled")
json.dump(spec, sys.stdout)
PY
xvfb-run -a pvpython tests/paraview/pv_read_check.py "$out/spec.json" > "$out/pv.log" 2>&1
rc=$?
grep -v "^$" "$out/pv.log" | grep -v "Skipping unrecognized" | tail -n 20
# ParaView's warning for an XDMF DataItem it cannot read; the files must give none
if grep -q "Skipping unrecognized" "$out/pv.log"; then fail "ParaView skipped data items"; fi
[ $rc -eq 0 ] || fail "ParaView does not read the results as written"
echo "PASS"
