#!/usr/bin/env bash
# End to end on the paper's case 7.2 (cases/rest_position, real fem_solver + dem_solver +
# coupler, strong coupling) with a DAMPED contact (COR < 1), the regime that used to create
# energy (docs/notes/damped_contact.md). Checks:
#  - static.json loads the cable with the sphere's weight from dem.json (4/3 pi R^3 rho g,
#    1e-5 relative), so the static reference is the one of eq. (43) for this sphere;
#  - Δt 3e-2, COR 0.1 and 0.5, 8 s: Point A comes to rest within 1 % of the FEM's own static
#    solution for the sphere's weight (static.json, eq. (43)); the peak deflection exceeds the
#    rest value by > 50 % (the transient overshoots: measured 0.497 and 0.509 vs 0.304 m); the
#    rest position does not depend on the COR (the two agree to 0.1 %); the sphere's mechanical
#    energy never rises above its start value by more than 1 J (no energy created at the
#    interface; without the Aitken restart safeguard COR 0.1 throws the sphere up with 27 kJ).
#    Why 3e-2 and not the case's 1e-2: at 1e-2 the bounce is damped too little to be at rest
#    within a test-length run (docs/notes/damped_contact.md: not within 1 % in 20 s for COR > 0.1). Part
#    of the damping at 3e-2 is Bossak's numerical damping of the 1 Hz sphere-on-cable mode
#    (docs/notes/centred_coupling.md); the fine-step reference is still bouncing at 2 s. The check is of
#    the rest POSITION, which no damping may change;
#  - Δt 1e-2 (the case's step), COR 0.5, 1.5 s: peak u_A within 5 % of the independent
#    fine-step reference computed here (scripts/analysis/reference_explicit.py 1.5 2e-5 0.5:
#    -0.5471 m; the scheme gives -0.5344) and no energy created (with coupling_force
#    end_of_step the net is thrown off the sphere and the sphere falls through).
. tests/e2e_lib.sh
case_dir=cases/rest_position
[ -d "$case_dir" ] || { echo "SKIP: $case_dir missing"; exit 77; }

"$NC_BIN/fem_solver" "$case_dir/static.json" --output "$NC_TMP/static" > "$NC_TMP/static.log" 2>&1 \
  || { cat "$NC_TMP/static.log"; fail "static solution failed"; }

run() {   # name, --set arguments
  local name=$1; shift
  run_case "$name" "$case_dir" "$@"
}
long() { run "$1" --set "dem.materials.0.restitution=$2" --set coupler.dt=3e-2 \
             --set fem.analysis.dt_s=3e-2 --set coupler.end_time=8 --set fem.analysis.end_time_s=8; }
long cor01 0.1
long cor05 0.5
run short --set dem.materials.0.restitution=0.5 --set coupler.end_time=1.5 \
          --set fem.analysis.end_time_s=1.5
"$PY" scripts/analysis/reference_explicit.py 1.5 2e-5 0.5 --save "$NC_TMP/ref.npz" \
  > "$NC_TMP/ref.log" 2>&1 || { tail "$NC_TMP/ref.log"; fail "reference_explicit.py failed"; }

"$PY" - "$NC_TMP" <<'PY' || exit 1
import sys, json, math, h5py, numpy as np
tmp = sys.argv[1]
with h5py.File(tmp + "/static/fem.h5", "r") as f:
    static = float(f["/monitor/displacement"][-1, 0, 2])
print("static Point A: %.5f m" % static)
st, dem = json.load(open("cases/rest_position/static.json")), json.load(open("cases/rest_position/dem.json"))
weight = 4 / 3 * math.pi * dem["particles"][0]["radius"] ** 3 * dem["materials"][0]["density_kg_m3"] * 9.81
load = -sum(p["force_n"][2] * len(p["nodes"]) for p in st["point_loads"])
print("static load %.3f N, sphere weight %.3f N" % (load, weight))
assert abs(load - weight) < 1e-5 * weight, "static.json does not carry the sphere's weight"

def summary(name):
    d = tmp + "/" + name
    with h5py.File(d + "/fem.h5", "r") as f:
        t = f["/monitor/time"][:]; uA = f["/monitor/displacement"][:, 0, 2]
    cfg = json.load(open(d + "/dem.json"))
    m = 4 / 3 * math.pi * cfg["particles"][0]["radius"] ** 3 * cfg["materials"][0]["density_kg_m3"]
    with h5py.File(d + "/dem.h5", "r") as f:
        z = f["/particles/position"][:, 0, 2]
        vz = f["/particles/velocity"][:, 0, 2]
    e = 0.5 * m * vz ** 2 + m * 9.81 * (z - z[0])
    tail = uA[t >= t[-1] - 0.5]
    return uA.min(), tail.mean(), np.abs(tail - static).max(), e.max()

rest = {}
for name in ("cor01", "cor05"):
    peak, mean, dev, emax = summary(name)
    print("%s: peak %.4f m, last 0.5 s mean %.5f m (max deviation %.2e m), max sphere energy "
          "%+.2f J" % (name, peak, mean, dev, emax))
    assert dev < 0.01 * abs(static), (name, dev)          # at rest within 1 %
    assert peak < 1.5 * static, (name, peak)              # overshoot beyond the rest value
    assert emax < 1.0, (name, emax)                       # no energy created
    rest[name] = mean
assert abs(rest["cor01"] - rest["cor05"]) < 1e-3 * abs(static), rest
ref_peak = float(np.load(tmp + "/ref.npz")["uA"].min())
peak, _, _, emax = summary("short")
print("short (dt 1e-2, COR 0.5): peak %.4f m (fine-step reference %.4f), max sphere energy %+.2f J"
      % (peak, ref_peak, emax))
assert abs(peak - ref_peak) < 0.05 * abs(ref_peak), peak
assert emax < 1.0, emax
PY
echo PASS
