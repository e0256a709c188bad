#!/usr/bin/env bash
# cases/steel_net: a 710 kg granite rock (E 3e10 Pa, restitution 0.2, friction 0.5,
# Hunt–Crossley) at 10 m/s on a 4 m steel wire-rope net (E 1e11 Pa, 0.16 kg nodes), strong
# coupling at the case's Δt 1e-3 s with the interface Jacobian, to 0.15 s (the peak deflection
# at 0.06 s, the rock thrown back by 0.1 s; ~4 s wall), and a fine-step reference at Δt 2e-4 s
# to 0.08 s (~6 s). Checks (tolerances inline):
#  - both runs are reliable: exit 0 (every strong step converged, the energy guard stayed
#    silent), coupling.h5 `converged` all 1 and no energy above the limit;
#  - the peak deflection of the centre node (220, z) at Δt 1e-3 s is within 3 % of the
#    reference's (measured −0.429 against −0.432 m);
#  - the rock's energy (kinetic + m g z) never rises above its value at the first contact step
#    by more than 1 % of it, and the net throws it back slower than it came: its largest
#    upward speed after the impact is below the impact speed (measured 9.6 of 10.0 m/s);
#  - the interface iteration is not a slow fixed point: at most 5 iterations per contact step
#    on average (measured 3.96; 3.75 before Aitken took α = 1 while the residual contracts,
#    4.05 when a step had at most 10 iterations before it was retried at half the Δt, 4.8
#    before the Hunt–Crossley impact speed was in the DEM's Jacobian and the predictor
#    quadratic; 5.5 before the FEM solved with the skew part of the contact's linearisation,
#    with 331 steps accepted unconverged);
#  - at restitution 0.1, to 0.03 s (~2 s; at least 20 ms in contact): every step
#    converged, exit 0. A kink of the contact law sent Aitken back to an input already tried
#    every third iteration until its safeguard restarted on a repeated input: before, this run
#    accepted 6 steps unconverged at Δt/64 (exit 3);
#  - the ropes above their breaking load (given at 70 kN) are listed by run_case before "done";
#  - the rock off the net's symmetry lines, at (0.037, 0.023) m, to 0.15 s (~3 s): every step
#    converged, exit 0, at most 6 iterations per contact step on average (measured 4.75), at
#    most 5 rejected tries (measured 2). With at most 10 iterations per step this run accepted
#    7 steps unconverged at Δt/64 (exit 3, 59 rejected tries): friction's stick and slip
#    change from one iteration to the next there at every Δt, so halving it did not help;
#  - weak coupling at the case's Δt, to 0.08 s (~1 s): the rock bounces off a net that hardly
#    deflects (measured 0.028 m against 0.429 m) and its contact damping takes the impact
#    energy, which the energy guard (energy created) cannot see; the impulse guard does: the
#    structure solved with a force that carried almost none of the rock's impulse (measured
#    100 % missed), NOT reliable, exit 3, and run_case does not say "done".
. tests/e2e_lib.sh
run_case run cases/steel_net --set coupler.end_time=0.15 \
  --set fem.element_sets.0.breaking_load_n=70000
run_case reference cases/steel_net --set coupler.end_time=0.08 --set coupler.dt=2e-4 \
  --set fem.analysis.dt_s=2e-4
run_case kink cases/steel_net --set coupler.end_time=0.03 --set fem.analysis.end_time_s=0.03 \
  --set dem.materials.0.restitution=0.1 --set dem.net_wall.restitution=0.1
run_case offcentre cases/steel_net --set coupler.end_time=0.15 \
  --set 'dem.particles.0.position=[0.037,0.023,0.45]'
"$PY" - "$NC_TMP/run" "$NC_TMP/reference" "$NC_TMP/kink" "$NC_TMP/offcentre" <<'PY' || exit 1
import json, math, sys
import h5py
import numpy as np
run, ref, kink, offcentre = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]


def peak(d):
    with h5py.File(d + "/fem.h5", "r") as f:
        ids = list(f["/monitor/node_ids"][()])
        return f["/monitor/displacement"][:, ids.index(220), 2].min()


for d in (run, ref, kink, offcentre):
    with h5py.File(d + "/coupling.h5", "r") as c:
        conv = c["steps/converged"][()]
        created, limit = c["energy/created"][()], c["energy/limit"][()]
        assert conv.all(), "%s: %d steps unconverged" % (d, int((conv == 0).sum()))
        assert (created <= limit).all(), "%s: energy created %.4g J above the limit" % (d, created.max())
with h5py.File(kink + "/coupling.h5", "r") as c:
    contact_time = float(c["steps/dt"][()][c["steps/in_contact"][()] > 0].sum())
# the rock must be on the net for most of the run, or the kink run tests nothing (measured
# 23.5 ms of the 30 ms, in contact from 6 ms on)
assert contact_time >= 0.02, "kink run: only %.4f s in contact" % contact_time
p, p_ref = peak(run), peak(ref)
print("peak deflection of the centre: %.4f m at dt 1e-3 s, %.4f m at 2e-4 s (%.2f %%)"
      % (p, p_ref, 100 * (p / p_ref - 1)))
assert abs(p / p_ref - 1) < 0.03, "the peak deflection differs from the fine-step reference by more than 3 %"

dem = json.load(open("cases/steel_net/dem.json"))
R = dem["particles"][0]["radius"]
mass = dem["materials"][0]["density_kg_m3"] * 4.0 / 3.0 * math.pi * R ** 3
with h5py.File(run + "/dem.h5", "r") as f:
    t = f["/time"][()]
    z = f["/particles/position"][:, 0, 2]
    vz = f["/particles/velocity"][:, 0, 2]
    ekin = f["/energy/kinetic"][()]
with h5py.File(run + "/coupling.h5", "r") as c:
    ct, inc, it = c["steps/time"][()], c["steps/in_contact"][()], c["steps/iterations"][()]
energy = ekin + mass * 9.81 * z
t_hit = ct[np.nonzero(inc)[0][0]]
before = np.nonzero(t <= t_hit)[0][-1]
after = energy[before + 1:]
v_in, v_out = -vz[before], vz[before + 1:].max()
print("rock: energy at first contact %.0f J, largest after %.0f J (%.4f); impact %.2f m/s, thrown back at %.2f m/s"
      % (energy[before], after.max(), after.max() / energy[before], v_in, v_out))
assert after.max() < 1.01 * energy[before], "energy was created at the interface"
assert 0 < v_out < v_in, "the rock left the net faster than it came, or was not thrown back"
print("iterations per contact step: %.2f (max %d)" % (it[inc > 0].mean(), it[inc > 0].max()))
assert it[inc > 0].mean() <= 5.0, "the interface iteration needs more iterations than expected"
with h5py.File(offcentre + "/coupling.h5", "r") as c:
    inc, it, rejected = c["steps/in_contact"][()], c["steps/iterations"][()], c["steps/rejected"][()]
print("off centre: %.2f iterations per contact step (max %d), %d rejected tries"
      % (it[inc > 0].mean(), it[inc > 0].max(), rejected.sum()))
assert inc.any(), "off centre: the rock never touched the net"
assert it[inc > 0].mean() <= 6.0, "off centre: more iterations per contact step than expected"
assert rejected.sum() <= 5, "off centre: more rejected tries than expected"
PY
# The ropes' breaking load (70 kN: a grade-1770 rope of 5e-5 m² metallic area) is only
# reported (the FEM only tracks it; the rope does not fail): the launcher lists the FEM's
# overload warning before "done" (measured 143.8 kN, 2.05x, in 120 elements). With
# fail_on_overload the verdict is exit 3 (tests/coupler/test_run_status.sh).
grep -q "^run_case: ropes above their breaking load" "$NC_TMP/run.out" \
  || fail "run_case did not report the ropes above their breaking load"
grep -q "set net: [0-9]* elements exceeded breaking_load_n 70000 N" "$NC_TMP/run.out" \
  || fail "run_case did not list the FEM's overload warning"
tail -n 1 "$NC_TMP/run.out" | grep -q "^run_case: done" || fail "run_case: not done after the overload report"
scripts/run_case.sh cases/steel_net --out "$NC_TMP/weak" --quiet --set coupler.scheme=weak \
  --set coupler.end_time=0.08 --set fem.analysis.end_time_s=0.08 > "$NC_TMP/weak.out" 2>&1
rc=$?
[ "$rc" -eq 3 ] || { tail -n 20 "$NC_TMP/weak.out"; fail "weak: exit $rc, expected 3 (impulse guard)"; }
grep -q "NOT reliable: the force the structure solved with carried .* less impulse" "$NC_TMP/weak/coupler.log" \
  || fail "weak: no impulse verdict"
grep -q "^run_case: done" "$NC_TMP/weak.out" && fail "weak: run_case says done"
"$PY" - "$NC_TMP/weak/coupling.h5" <<'PY' || fail "weak: coupling.h5 status"
import sys, h5py
with h5py.File(sys.argv[1], "r") as f:
    a = f.attrs
    print("weak: impulse missed %.1f %%, reliable %d" % (100 * a["impulse_missed_share"], a["reliable"]))
    assert a["impulse_loss"] == 1 and a["reliable"] == 0 and a["impulse_missed_share"] > 0.5
PY
echo "PASS"
