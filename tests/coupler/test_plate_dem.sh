#!/usr/bin/env bash
# Swapping a solver: the Python spring plate (scripts/participants/spring_plate.py, written from
# the protocol description only) stands in for the FEM against the real dem_solver. A 0.1 m
# rock (ρ = 2500 kg/m³, m = 10.472 kg) released 5 mm above the plate comes to rest on it; the
# analytic static deflection is w = -m g / k = -1.0273e-2 m (k = 1e4 N/m). Tolerance 0.5 %
# (the half-critically damped plate has settled to ~1e-5 relative after 1.5 s; the contact
# overlap does not enter w). Also the force on the plate must equal the rock's weight (0.5 %),
# and both speak protocol version 2.
set -u
: "${NC_BIN:?}" "${NC_TMP:?}"
PY=${PYTHON:-/usr/bin/python3}
if [ ! -x "$NC_BIN/dem_solver" ]; then
  echo "SKIP: $NC_BIN/dem_solver not built"; exit 77
fi
out=$NC_TMP/plate_dem
scripts/run_case.sh tests/coupler/cases/plate_dem --out "$out" \
  --fem-program "$PY scripts/participants/spring_plate.py" >"$NC_TMP/plate_dem.out" 2>&1 \
  || { echo "FAIL: run_case.sh failed"; tail -n 20 "$out"/*.log; exit 1; }
# the Python plate and the C dem_solver agree on protocol version 2
grep -Eq "fem = netcouple spring_plate.py \(tcp://[^,]*, protocol 2\), dem = .*, protocol 2\)" \
  "$out/coupler.log" || { echo "FAIL: not protocol 2: $(head -n 1 "$out/coupler.log")"; exit 1; }
"$PY" - "$out" <<'PY' || exit 1
import sys, math, h5py, numpy as np
d = sys.argv[1]
m = 2500.0 * 4.0 / 3.0 * math.pi * 0.1 ** 3
w_exact = -m * 9.81 / 1e4
plate = np.loadtxt(d + "/plate.csv", delimiter=",", skiprows=1)
w = plate[-1, 1]
print("plate deflection %.6e m, analytic -m g / k = %.6e m" % (w, w_exact))
assert abs(w - w_exact) < 5e-3 * abs(w_exact), (w, w_exact)
with h5py.File(d + "/coupling.h5", "r") as f:
    fz = f["/steps/contact_force"][-1, 2]
    assert f["/steps/converged"][:].all()
print("force on the plate %.4f N, weight %.4f N" % (fz, -m * 9.81))
assert abs(fz + m * 9.81) < 5e-3 * m * 9.81
PY
echo PASS
