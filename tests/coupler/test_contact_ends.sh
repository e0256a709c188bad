#!/usr/bin/env bash
# End to end: contacts that end within a step, with the interface Jacobian, Aitken from the
# full step, interface_compliance and newton_estimate 0.1 (docs/notes/contact_backtracking.md
# "A search for the contact's end instead of halving"; docs/notes/interface_jacobian.md,
# item 7).
#
# Both runs keep the contact model they were measured with, eq. (A.5)'s dashpot ("damping":
# "fit") for cable_impact and the force of the last sub-step ("coupling_force": "end_of_step")
# for angled_net: the cases now have the Hunt–Crossley dashpot and the step's average force,
# with which these contact ends are gentler (docs/notes/interface_jacobian.md, item 10).
#
# cases/cable_impact (a 5.4 t sphere bouncing on a cable) at rock–cable restitution 0.3 and its
# Δt 0.01 s, 0.55 s: in steps 24 and 46 the rock leaves the cable within the step. The DEM's
# search with the structure's compliance found no contact consistent there, and once the
# compliance was dropped, halving back to the first point with contact crept towards the
# converged force from the deep side (−28.8 kN, −16.4 kN, −6.4 kN, … −127 N): 17 and 13
# iterations. Such a contact-free answer then ended the compliance for the try, and contact
# backtracking searched along the step for the contact's end (cpl_contact_search.c): at most
# 5 iterations in a step, 93 in all, with two tries gone on without the compliance and 37
# backtracking solves. With up to 60 evaluations instead of 12 the DEM's search finds the
# contact's end itself (dem_compliance.h): 88 iterations, at most 3 in a step, no try without
# the compliance, no backtracking. Checks:
#  - reliable, exit 0; no try went on without the compliance;
#  - no step needs more than 10 interface iterations, its rejected tries counted too;
#  - the DEM's log notes, once, that its dashpot of eq. (A.5) makes the Jacobian unbounded
#    where a contact begins or ends (dem_solver/README.md "Contact model"), naming the
#    restitution. Two short runs more (0.03 s, before the contact): with the rock at 0.3 and
#    net_wall.restitution 1 the pair's damping is half the rock's, and the note names both;
#    with both at 1 there is no dashpot and no note; both reliable.
#
# cases/angled_net at restitution 0.1 and 5× its Δt (1e-3 s), 0.12 s: in step 96 the search
# leaves the iterate just inside a contact's end, where the dashpot's K grows like δ^(−3/4).
# The structure's answer then stays within eq. (35)'s tolerance of its input whatever the
# force, and that step was accepted with the particles' force at 439 N and the structure's at
# about 46 N: over the whole run the impulse guard fired at 11 % (NOT reliable). Convergence
# now also needs the guard's share, with the step accepted, or the step's own share within
# half of impulse_tolerance (force_mismatch in coupler/cpl_loop.c). Checks (measured over 0.12 s: the structure missed 0.07 % of the
# impulse; 31 % with the check off, impulse_tolerance 0):
#  - reliable, exit 0, every step converged;
#  - the structure missed at most 1 % of the particles' impulse (coupling.h5
#    impulse_missed_share).
# The same run with at most 4 iterations a step, no smaller step (dt_min = Δt) and unconverged
# steps accepted (opted in): the steps accepted unconverged leave the run's share far above
# the limit, and a check against the run's share alone then failed every later step too (112
# of 200 unconverged); a step within the limit of its own force still converges (measured 25
# of 200 unconverged; 3 now). At its graze in step 135 the DEM's K reaches 3e13 N/m or more,
# and the FEM's Newton sits at its rounding floor, 1.6e-3 N against a tolerance of 2.1e-8 N;
# with no smaller step allowed, the run stopped there until the FEM's rounding floor counted
# the rounding of the linearisation's K (u - u^k) (fem_solver/fem_analysis.c). Checks: it runs
# to its end; at
# most 50 unconverged steps; the opt-ins named in the verdict.
. tests/e2e_lib.sh
for c in cable_impact angled_net; do
  [ -d cases/$c ] || { echo "SKIP: cases/$c missing"; exit 77; }
done
options=(--set coupler.interface_jacobian=true --set coupler.relaxation.method=aitken
         --set coupler.relaxation.alpha=1.0 --set coupler.relaxation.first_iteration_cap=1.0
         --set coupler.work_tolerance=0 --set coupler.newton_estimate=0.1
         --set coupler.interface_compliance=true)
OPENBLAS_NUM_THREADS=1 run_case leaves cases/cable_impact "${options[@]}" --set coupler.dt=0.01 --set fem.analysis.dt_s=0.01 \
  --set coupler.end_time=0.55 --set fem.analysis.end_time_s=0.55 \
  --set dem.materials.0.restitution=0.3 --set dem.damping=fit
run_case angled cases/angled_net "${options[@]}" --set coupler.dt=0.001 --set fem.analysis.dt_s=0.001 \
  --set coupler.end_time=0.12 --set fem.analysis.end_time_s=0.12 \
  --set dem.materials.0.restitution=0.1 --set dem.net_wall.restitution=0.1 \
  --set dem.net_wall.coupling_force=end_of_step
run_case capped cases/angled_net "${options[@]}" --set coupler.dt=0.001 --set fem.analysis.dt_s=0.001 \
  --set coupler.end_time=0.2 --set fem.analysis.end_time_s=0.2 \
  --set dem.materials.0.restitution=0.1 --set dem.net_wall.restitution=0.1 \
  --set dem.net_wall.coupling_force=end_of_step --set coupler.max_iterations=4 \
  --set coupler.step_control.dt_min=0.001 \
  --set coupler.accept_unconverged=true --set coupler.accept_impulse_loss=true
short=(--set coupler.end_time=0.03 --set fem.analysis.end_time_s=0.03 --set dem.damping=fit)
run_case half cases/cable_impact "${options[@]}" "${short[@]}" \
  --set dem.materials.0.restitution=0.3 --set dem.net_wall.restitution=1.0
run_case undamped cases/cable_impact "${options[@]}" "${short[@]}" \
  --set dem.net_wall.restitution=1.0
expect_reliable leaves angled half undamped
grep -q '^dem_solver: note: dem.json: damping "fit" on net contacts (material "rock", restitution 0.3 and net_wall restitution 1): ' \
  "$NC_TMP/half/dem.log" || fail "half: the DEM did not note the dashpot of a pair damped by one side"
[ -f "$NC_TMP/undamped/dem.log" ] && ! grep -q "^dem_solver: note: .*dashpot" "$NC_TMP/undamped/dem.log" \
  || fail "undamped: the DEM noted a dashpot its contacts do not have"
grep -q "^coupler: results are NOT reliable: [0-9]* of [0-9]* steps were accepted without converging.*accepted because coupler.json sets accept_unconverged" \
  "$NC_TMP/capped/coupler.log" || fail "capped: the verdict does not say the steps were accepted unconverged"
[ "$(grep -c '^dem_solver: note: dem.json: damping "fit" on net contacts (material "rock", restitution 0.3): ' \
     "$NC_TMP/leaves/dem.log")" = 1 ] || fail "leaves: the DEM did not note its dashpot once"
grep -Eq "^coupler: interface compliance: .*; 0 of [0-9]+ tries went on without it" \
  "$NC_TMP/leaves/coupler.log" || fail "leaves: a try went on without the compliance: $(grep "interface compliance:" "$NC_TMP/leaves/coupler.log")"

"$PY" - "$NC_TMP" <<'PY' || exit 1
import sys, h5py, numpy as np
tmp = sys.argv[1]
with h5py.File(tmp + "/leaves/coupling.h5", "r") as f:
    tries = np.bincount(np.array(f["/iterations/step"]).astype(int).ravel())
    print("leaves: %d steps, at most %d interface iterations in a step (every try counted)"
          % (len(f["/steps/iterations"]), tries.max()))
    assert tries.max() <= 10, "leaves: a step took %d interface iterations" % tries.max()
with h5py.File(tmp + "/angled/coupling.h5", "r") as f:
    share = float(f.attrs["impulse_missed_share"])
    unconverged = int((np.array(f["/steps/converged"]) == 0).sum())
    print("angled: the structure missed %.3g %% of the impulse, %d unconverged steps" % (100 * share, unconverged))
    assert unconverged == 0, "angled: unconverged steps accepted"
    assert share <= 0.01, "angled: the structure missed %.3g %% of the impulse" % (100 * share)
with h5py.File(tmp + "/capped/coupling.h5", "r") as f:
    unconverged = int((np.array(f["/steps/converged"]) == 0).sum())
    steps = len(f["/steps/converged"])
    print("capped: %d of %d steps unconverged, the structure missed %.3g %% of the impulse"
          % (unconverged, steps, 100 * float(f.attrs["impulse_missed_share"])))
    assert 0 < unconverged <= 50, "capped: %d of %d steps unconverged" % (unconverged, steps)
print("PASS")
PY
