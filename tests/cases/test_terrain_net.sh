#!/usr/bin/env bash
# cases/terrain_net (paper 7.6): a rock (sphere R 0.3 m) rolls down the STL slope of the case
# and strikes a standing net at x = 6 m. Shortened to 2.6 s (first impact at ~1.9 s; ~10 s wall).
# Checks (tolerances stated inline):
#  - the run ends normally, every strong step converged;
#  - the rock rolled down the STL terrain: it reaches the run-out (x > 5 m) at 5-6.5 m/s
#    (rolling without slip down the 2.4 m drop of the rock centre gives sqrt(10/7 g h) =
#    5.8 m/s; the window allows for the bumps, the slip at the start and the rolling losses);
#  - the net stops it: first contact between 1.8 and 2.0 s, the rock centre never gets further
#    than x = 6.5 m (net plane 6 m + the net's deflection), and after the impact it moves back
#    (v_x < 0 at the end) at less than its impact speed (no energy created at the interface);
#  - the net deflects at the impact point (node 52, x displacement 0.1-0.6 m).
. tests/e2e_lib.sh
run_case run cases/terrain_net --set coupler.end_time=2.6
"$PY" - "$NC_TMP/run" <<'PY' || exit 1
import sys, numpy as np
sys.path.insert(0, "tests/cases")
from case_summary import load
r = load(sys.argv[1])
assert abs(r["ct"][-1] - 2.6) < 1e-9, r["ct"][-1]
assert r["conv"].all(), "%d strong steps did not converge" % int((r["conv"] == 0).sum())
x, v = r["pos"][:, 0, :], r["vel"][:, 0, :]
k5 = np.nonzero(x[:, 0] > 5.0)[0][0]
print("rock at x = 5 m: t %.2f s, v_x %.2f m/s" % (r["t"][k5], v[k5, 0]))
assert 5.0 < v[k5, 0] < 6.5, "the rock did not roll down the slope as expected"
inc = np.nonzero(r["inc"])[0]
assert len(inc) > 0, "the rock never touched the net"
t_hit = r["ct"][inc[0]]
print("first contact %.3f s, max rock x %.3f m, end v_x %.3f m/s, end x %.3f m"
      % (t_hit, x[:, 0].max(), v[-1, 0], x[-1, 0]))
assert 1.8 < t_hit < 2.0, "first contact at an unexpected time"
assert x[:, 0].max() < 6.5, "the rock went through the net"
assert v[-1, 0] < 0 and x[-1, 0] < 6.0, "the rock is not moving back from the net"
speed_before = np.linalg.norm(v[k5]); speed_after = np.linalg.norm(v[-1])
assert speed_after < speed_before, "energy was created at the interface"
ux = r["mu"][:, 0, 0]
print("node 52 max x deflection %.3f m; iterations/step %.2f (max %d)" % (ux.max(), r["it"].mean(), r["it"].max()))
assert 0.1 < ux.max() < 0.6, "unexpected net deflection"
PY
echo "PASS"
