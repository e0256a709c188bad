#!/usr/bin/env bash
# cases/angled_net (paper 7.5, Table 2): the paper's window 0-0.2 s run four times
# (strong 2e-4, weak 2e-4, weak 1e-4, weak 5e-5; about 15 s of wall time together). Checks:
#  - strong 2e-4: the small sphere (R 0.05) flies through a mesh opening untouched: it ends
#    beyond the net plane (z < -0.5 m) with the free-flight velocity (|v - v_free| < 1e-3 m/s);
#  - the large sphere (R 0.21) is held in the paper's window: still in contact with the net in
#    the last step, overlap < 0.02 m (measured 6.6 mm), slowed along the net normal compared
#    with free flight (> 0.05 m/s, measured 0.104). "Caught" means no more than this: with
#    Table 2's EA = 8.8 N the net only deflects the 97 kg rock, which leaves it past the lower
#    fixed edge at about 0.45 s (an angled net guides rocks rather than stopping them);
#  - the centre node (monitor 0) reaches -0.6 m +- 0.15 m (paper fig. 20a: about -0.6 m);
#  - strong 2e-4 matches weak coupling: max |u_z difference| over 0-0.2 s < 2 % of the peak
#    against weak 5e-5 (measured 1.1 %). Weak 1e-4 keeps the contact but is not accurate
#    during the impact: < 15 % against strong 2e-4 (measured 13.3 %, 12.5 % against weak
#    5e-5: its own error, which halving the step removes; 5.2 % at 0.2 s). The paper has strong
#    2e-4 match weak 1e-4 (fig. 20a); here that held within 4 % only while a node on the
#    rock's path (the rope line x = 0) was one contact for both ropes through it, which left
#    the crossing rope out (docs/notes/interface_jacobian.md, "A node is touched once per
#    rope"): with both ropes touched the contact is stiffer and 1e-4 is near the plain
#    exchange's limit for the 0.03 kg nodes;
#  - weak 2e-4 "loses contact": its centre node departs from weak 1e-4 by > 50 % of the peak
#    (the net is flung off and the rock thrown back, fig. 19a); it creates energy (the
#    coupler's energy guard fires; the run opts in with accept_energy_growth, the warning is
#    checked), weak 1e-4 and 5e-5 do not (measured: 134 MJ created at 2e-4, where the impact
#    brings 4.7 kJ; at 1e-4 and 5e-5 none, their interface work mismatch 38 J and 3.8 J,
#    strong 2e-4's 1.7 J).
# The weak runs are the paper's plain exchange ("interface_jacobian": false).
. tests/e2e_lib.sh
run_case strong2 cases/angled_net
run_case weak2 cases/angled_net --set coupler.scheme=weak --set coupler.accept_energy_growth=true \
  --set coupler.interface_jacobian=false
grep -q "^warning: step [0-9]* (t = .* s): the run has created .* J of energy" \
  "$NC_TMP/weak2/coupler.log" || fail "weak2: no energy-created warning"
run_case weak1 cases/angled_net --set coupler.scheme=weak --set coupler.dt=1e-4 \
  --set coupler.interface_jacobian=false
run_case weak05 cases/angled_net --set coupler.scheme=weak --set coupler.dt=5e-5 \
  --set coupler.interface_jacobian=false
"$PY" - "$NC_TMP" <<'PY' || exit 1
import sys, h5py, numpy as np
sys.path.insert(0, "tests/cases")
from case_summary import load
d = sys.argv[1]
s, w1, w2, w05 = (load(d + "/" + n) for n in ("strong2", "weak1", "weak2", "weak05"))
g = np.array([0, -6.936718, -6.936718]); v0 = np.array([0, -5.54, -5.54])
T = s["t"][-1]
assert abs(T - 0.2) < 1e-9, T
v_free = v0 + g * T
# small sphere (particle 1): through an opening, never touched
ps, vs = s["pos"][-1, 1], s["vel"][-1, 1]
print("small sphere end z %.3f m, |v - v_free| %.2e m/s" % (ps[2], np.linalg.norm(vs - v_free)))
assert ps[2] < -0.5, "small sphere did not pass the net plane"
assert np.linalg.norm(vs - v_free) < 1e-3, "small sphere touched the net"
# large sphere (particle 0): held by the net
with h5py.File(d + "/strong2/coupling.h5", "r") as f:
    gap = float(f["/steps/min_gap"][-1]); inc = int(f["/steps/in_contact"][-1])
vl = s["vel"][-1, 0]
print("large sphere: in contact %d, gap %.4f m, v_z %.3f (free %.3f) m/s" % (inc, gap, vl[2], v_free[2]))
assert inc == 1 and gap > -0.02, "large sphere is not held by the net at 0.2 s"
assert vl[2] > v_free[2] + 0.05, "the net did not slow the large sphere"
# centre node
t = s["mt"]
us = s["mu"][:, 0, 2]
u1 = np.interp(t, w1["mt"], w1["mu"][:, 0, 2])
u2 = np.interp(t, w2["mt"], w2["mu"][:, 0, 2])
u05 = np.interp(t, w05["mt"], w05["mu"][:, 0, 2])
peak = np.abs(u1).max()
print("centre node: strong2 min %.3f, weak1 min %.3f, max|strong2-weak1| %.4f (%.1f %%), max|weak2-weak1| %.3f m"
      % (us.min(), u1.min(), np.abs(us - u1).max(), 100 * np.abs(us - u1).max() / peak, np.abs(u2 - u1).max()))
assert -0.75 < us.min() < -0.45, "centre node deflection not about -0.6 m"
print("centre node: max|strong2-weak05| %.4f m (%.1f %%), max|weak1-weak05| %.4f m (%.1f %%)"
      % (np.abs(us - u05).max(), 100 * np.abs(us - u05).max() / peak, np.abs(u1 - u05).max(),
         100 * np.abs(u1 - u05).max() / peak))
assert np.abs(us - u1).max() < 0.15 * peak, "weak 1e-4 departs from strong 2e-4 by > 15 %"
assert np.abs(us - u05).max() < 0.02 * peak, "strong 2e-4 does not match weak 5e-5"
assert np.abs(u2 - u1).max() > 0.5 * peak, "weak 2e-4 did not lose contact (paper fig. 19a)"
its = h5py.File(d + "/strong2/coupling.h5", "r")["/steps/iterations"][:]
print("strong 2e-4: %.2f iterations per step, max %d" % (its.mean(), its.max()))
PY
echo "PASS"
