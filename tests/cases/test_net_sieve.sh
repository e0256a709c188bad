#!/usr/bin/env bash
# cases/net_sieve (paper 7.7, fig. 25): a small sphere (R 0.05 m) falls through an opening of
# a coarse net (0.25 m mesh) while a big one (R 0.2 m) is stopped and thrown back. The full
# case: 0.2 s (the paper's window), ~2 s wall. Checks:
#  - every strong step converged;
#  - small sphere: ends below the net (z < -0.5 m) with the free-fall velocity
#    (-5 - 9.81 t, |difference| < 1e-3 m/s: it never touched a cable);
#  - big sphere: stopped above the net (its centre never below z = -0.25 m, the cables are
#    0.125 m from its centre line) and thrown back: moving up (v_z > 2 m/s) at the end, its
#    upward speed never above its impact speed (no energy created at the interface);
#  - the run is reliable (exit 0, the coupler says so): no energy created anywhere. Before the
#    DEM's sliding spring was limited (dem_solver/README.md "Contact model"), the big sphere's
#    first contact, found deep within the DEM's single sub-step, stored 31.5 J of tangential
#    spring energy that no work had put in (2.3 % of the input) and the guard fired.
. tests/e2e_lib.sh
run_case run cases/net_sieve
grep -q "^coupler: results are reliable" "$NC_TMP/run/coupler.log" || fail "the run is not reported reliable"
if grep -q "the run has created" "$NC_TMP/run/coupler.log"; then fail "the energy guard fired"; fi
"$PY" - "$NC_TMP/run" <<'PY' || exit 1
import sys, numpy as np
sys.path.insert(0, "tests/cases")
from case_summary import load
r = load(sys.argv[1])
T = r["ct"][-1]
assert abs(T - 0.2) < 1e-9, T
assert r["conv"].all(), "%d strong steps did not converge" % int((r["conv"] == 0).sum())
ps, vs = r["pos"][-1, 1], r["vel"][-1, 1]
dv = np.linalg.norm(vs - np.array([0, 0, -5.0 - 9.81 * T]))
print("small sphere: end z %.3f m, |v - v_free| %.2e m/s" % (ps[2], dv))
assert ps[2] < -0.5, "the small sphere did not fall through the net"
assert dv < 1e-3, "the small sphere touched the net"
zb, vb = r["pos"][:, 0, 2], r["vel"][:, 0, :]
speed = np.linalg.norm(vb, axis=1)
k_hit = np.nonzero(r["t"] >= r["ct"][np.nonzero(r["inc"])[0][0]])[0][0]
print("big sphere: min z %.3f m, impact speed %.3f, end v_z %.3f, max upward v_z %.3f m/s"
      % (zb.min(), speed[k_hit], vb[-1, 2], vb[:, 2].max()))
assert zb.min() > -0.25, "the big sphere went through the net"
assert vb[-1, 2] > 2.0, "the big sphere was not thrown back"
assert vb[:, 2].max() < speed[k_hit], "thrown back faster than it came: energy created at the interface"
print("net node 30 min u_z %.3f m; iterations/step %.2f (max %d)" % (r["mu"][:, 0, 2].min(), r["it"].mean(), r["it"].max()))
PY
echo "PASS"
