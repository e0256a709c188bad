#!/usr/bin/env bash
# End to end: the three real programs (fem_solver, dem_solver, coupler) on localhost on a small
# case (tests/coupler/cases/small_net: 7 x 7 cable net, one rock), started by run_case.sh.
# Checks: all exit 0 (weak at 1e-3 s: 3, the impulse guard); every strong step converged; the result files exist and their XDMF files
# describe the HDF5 output exactly (tests/xdmf_check.py); and an independent
# balance: the rock's momentum change from dem.h5 equals the impulse of gravity minus the
# impulse of the forces the coupler recorded on the net (m Δv = -Σ F_z Δt + m g T), to 1e-6
# of m g T (the DEM's reply is the exact time average of its contact force).
. tests/e2e_lib.sh

check() {   # dir scheme [rock density]
  for f in coupling.h5 iterations.log fem.h5 dem.h5 fem.xdmf particles.xdmf dem_net.xdmf fem.log dem.log coupler.log; do
    [ -s "$1/$f" ] || fail "$1/$f missing"
  done
  # both XDMF files describe their HDF5 output exactly (tests/xdmf_check.py)
  "$PY" tests/xdmf_check.py "$1/fem.xdmf" /output/time || fail "$1/fem.xdmf"
  "$PY" tests/xdmf_check.py "$1/particles.xdmf" /time || fail "$1/particles.xdmf"
  "$PY" tests/xdmf_check.py "$1/dem_net.xdmf" /time || fail "$1/dem_net.xdmf"
  "$PY" - "$1" "$2" "${3:-2500}" <<'PY' || exit 1
import sys, math, h5py, numpy as np
d, scheme, density = sys.argv[1], sys.argv[2], float(sys.argv[3])
m = density * 4.0 / 3.0 * math.pi * 0.12 ** 3
with h5py.File(d + "/coupling.h5", "r") as f:
    n = f["/steps/time"].shape[0]
    assert n == 400, n
    if scheme == "strong":
        assert f["/steps/converged"][:].all(), "unconverged steps"
    assert f["/steps/in_contact"][:].any(), "the rock never touched the net"
    impulse = float((f["/steps/contact_force"][:, 2] * f["/steps/dt"][:]).sum())
    T = float(f["/steps/dt"][:].sum())
with h5py.File(d + "/dem.h5", "r") as f:
    t = f["/time"][:]
    assert len(t) == 41, len(t)   # outputs every 0.01 s up to 0.4 s
    assert abs(t - 0.01 * np.arange(41)).max() < 1e-12, t   # at exact multiples of the interval
    assert f["/particles/velocity"].shape == (41, 1, 3), f["/particles/velocity"].shape
    vz = float(f["/particles/velocity"][-1, 0, 2])
# every dataset of the three files carries its units
for name in ("fem.h5", "dem.h5", "coupling.h5"):
    with h5py.File(d + "/" + name, "r") as f:
        missing = []
        f.visititems(lambda n, o: missing.append(n) if isinstance(o, h5py.Dataset) and "units" not in o.attrs else None)
        assert not missing, (name, "datasets without units", missing)
lhs = m * (vz - (-0.5))
rhs = -impulse + m * -9.81 * T
print("%s: m dv = %.9f, -impulse + m g T = %.9f N s" % (d, lhs, rhs))
assert abs(lhs - rhs) < 1e-6 * m * 9.81 * T, (lhs, rhs)
PY
}

run() {   # name, --set arguments
  local name=$1; shift
  run_case "$name" tests/coupler/cases/small_net "$@"
}

run strong_aitken
check "$NC_TMP/strong_aitken" strong
# the XDMF check fails on broken copies of a coupled run's particles.xdmf and dem_net.xdmf
for x in particles.xdmf dem_net.xdmf; do
  "$PY" tests/xdmf_check.py --self-test "$NC_TMP/strong_aitken" $x /time "$NC_TMP" \
    || fail "xdmf_check self-test $x"
done
run strong_iqn --set coupler.relaxation.method=iqn-ils --set coupler.relaxed_quantity=force
check "$NC_TMP/strong_iqn" strong
# weak coupling with the plain exchange is unstable for the 18 kg rock on this light net at
# this step (the paper's point), and even a 3.6 kg rock creates energy during the impact
# (up to 9 J above its start, input 12.8 J; the energy guard fires at t = 0.089 s): opted in,
# the warning checked.
run weak_plain --set coupler.scheme=weak --set dem.materials.0.density_kg_m3=500 \
  --set coupler.accept_energy_growth=true --set coupler.interface_jacobian=false
grep -q "^warning: step [0-9]* (t = .* s): the run has created .* J of energy" \
  "$NC_TMP/weak_plain/coupler.log" || fail "weak_plain: no energy-created warning"
check "$NC_TMP/weak_plain" weak 500
# With the interface Jacobian (the default) the same weak exchange holds the 18 kg rock without
# creating energy, but at 1e-3 s the structure solves with 40 % less impulse than the rock's
# contact forces gave it (the linearisation takes the force back as the light net moves away
# within the step, and the DEM's contact damping absorbs what the net should: the net's peak
# 0.052 m against strong coupling's 0.066 m): the impulse guard says NOT reliable, exit 3.
# At 2e-4 s the share is 0.8 % and the peak within 1 % of strong coupling's: exit 0.
scripts/run_case.sh tests/coupler/cases/small_net --out "$NC_TMP/weak" --quiet \
  --set coupler.scheme=weak > "$NC_TMP/weak.out" 2>&1
rc=$?
[ "$rc" -eq 3 ] || { tail -n 20 "$NC_TMP/weak.out"; fail "weak 1e-3: exit $rc, expected 3 (impulse guard)"; }
grep -q "results are NOT reliable: the force the structure solved with carried .* less impulse than the particles' contact forces" \
  "$NC_TMP/weak/coupler.log" || fail "weak 1e-3: no impulse verdict"
grep -q "created .* J of energy" "$NC_TMP/weak/coupler.log" && fail "weak: energy created"
check "$NC_TMP/weak" weak
run weak_fine --set coupler.scheme=weak --set coupler.dt=2e-4
"$PY" - "$NC_TMP" <<'PY' || fail "weak 2e-4 against strong coupling"
import sys, h5py, numpy as np
d = sys.argv[1]
peak = {}
for run in ("strong_aitken", "weak_fine", "weak"):
    with h5py.File("%s/%s/fem.h5" % (d, run), "r") as f:
        peak[run] = float(np.abs(f["/monitor/displacement"][:]).max())
    with h5py.File("%s/%s/coupling.h5" % (d, run), "r") as f:
        peak[run + "_share"] = float(f.attrs["impulse_missed_share"])
        peak[run + "_loss"] = int(f.attrs["impulse_loss"])
print(peak)
assert abs(peak["weak_fine"] - peak["strong_aitken"]) < 0.01 * peak["strong_aitken"], peak
assert peak["weak_fine_share"] < 0.05 and peak["weak_fine_loss"] == 0, peak
assert peak["weak_share"] > 0.05 and peak["weak_loss"] == 1, peak
assert peak["strong_aitken_share"] < 1e-4 and peak["strong_aitken_loss"] == 0, peak
PY

# the paper's efficiency options with the real solvers: rock released 0.48 m above the net,
# 10 x larger steps while the DEM reports it far (near_distance 0.2 m), no FEM solve before
# the first contact force
run efficiency --set coupler.efficiency.far_step=true --set coupler.efficiency.far_step_factor=10 \
  --set coupler.efficiency.skip_fem_without_contact=true --set dem.particles.0.position.2=0.6 \
  --set dem.net_wall.near_distance_m=0.2
"$PY" - "$NC_TMP/efficiency" <<'PY' || exit 1
import sys, h5py, numpy as np
d = sys.argv[1]
with h5py.File(d + "/coupling.h5", "r") as f:
    dt = f["/steps/dt"][:]
    assert abs(f["/steps/time"][-1] - 0.4) < 1e-12
    assert f["/steps/converged"][:].all()
    assert f["/steps/in_contact"][:].any()
    big = np.isclose(dt, 0.01).sum()
    assert big >= 10, big                      # free fall in large steps
    assert np.isclose(dt, 0.001).sum() >= 50   # small steps near and in contact
    solved = f["/iterations/fem_solved"][:]
    steps = f["/iterations/step"][:]
    fem_steps = len(np.unique(steps[solved == 1]))
    # FEM skipped while no contact force acted, solved once it did
    assert 0 < fem_steps < len(dt), (fem_steps, len(dt))
    assert (solved[f["/iterations/contact_force"][:, 2] != 0] == 1).all()
print("efficiency: %d steps (%d large), FEM solved in %d" % (len(dt), big, fem_steps))
PY

# the rock placed inside the net by mistake (its centre 5 cm above the flat net, radius 12 cm):
# the DEM refuses at the first step, naming the particle and how deep, before any result
# step is written; a rock touching the net (centre 12 cm above) starts
scripts/run_case.sh tests/coupler/cases/small_net --out "$NC_TMP/inside" --quiet \
  --set 'dem.particles.0.position=[0,0,0.05]' > "$NC_TMP/inside.out" 2>&1
rc=$?
[ "$rc" -eq 1 ] || { cat "$NC_TMP/inside.out"; fail "rock inside the net: exit $rc, expected 1"; }
grep -q "particle 0 starts 0.07 m inside the net (58 % of its radius 0.12 m" "$NC_TMP/inside.out" \
  || { cat "$NC_TMP/inside.out"; fail "rock inside the net: not said"; }
grep -q "^run_case: failed: dem" "$NC_TMP/inside.out" || fail "rock inside the net: the DEM not named"
run_case touching tests/coupler/cases/small_net --set 'dem.particles.0.position=[0,0,0.12]' \
  --set coupler.end_time=0.01 --set fem.analysis.end_time_s=0.01
echo PASS
