#!/usr/bin/env python3
"""linear_stability_damped.py [C] — linear_stability.py with the contact DASHPOT (COR < 1).

Same 2-dof model as linear_stability.py (sphere 253 kg -- contact spring K 5.7e5 N/m and now a
dashpot C -- cable node 0.66 kg -- cable spring 9000 N/m, Rayleigh tau 5), converged strong step
(the fixed point over the interface displacement AND velocity is solved exactly; the map is
affine). The DEM force on the sphere in sub-step j is K (w_j - X) + C (wdot_j - V); what matters
here is which wall velocity wdot_j the DEM uses:
  'avg'    (u_n+1 - u_n) / dt in every sub-step (what dem_solver does: the received
           `velocity` array is unused)
  'interp' v_n + (j+1)/N (v_n+1 - v_n): linear from the start-of-step velocity to the received
           end velocity, so the last sub-step (the force returned with end_of_step) uses v_n+1
           (tried in dem_solver and reverted: damped_contact.md)
  'end'    v_n+1 in every sub-step
Reply to the FEM: 'last' (coupling_force end_of_step) or 'avg' (impulse / dt).
C defaults to the dem_solver dashpot at the static load for COR 0.5: 2 zeta sqrt(m* kn') with
zeta 0.233 (fit A.8-A.10), m* = sphere mass, kn' = 5.79e5 -> 5.6e3 N s/m.
Prints the eigenvalues per step (|lambda| for complex pairs with their frequency and zeta; the
signed value for real ones: a negative real eigenvalue is an alternating overshoot, which with
a unilateral contact means the node is thrown off the particle). 'ga' 0 = generalized-alpha
rho_inf 0 (alpha_m -1, alpha_f 0: L-stable, load still at t_n+1)."""
import sys
import numpy as np

import os
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from linear_stability import MS, M, K, KC, TAU, DT_DEM, weights  # noqa: E402


def step(state, u1, v1, dt, N, C, wmode, reply, integ, par):
    X, V, u, v, a = state
    h = dt / N; imp = 0.0; flast = 0.0
    for j in range(N):
        fr = (j + 1) / N
        w = u + fr * (u1 - u)
        wd = {'avg': (u1 - u) / dt, 'interp': v + fr * (v1 - v), 'end': v1}[wmode]
        f = K * (w - X) + C * (wd - V)       # on the sphere
        V += h * f / MS; X += h * V
        imp -= h * f; flast = -f
    F = {'avg': imp / dt, 'last': flast}[reply]
    b, g, am, af = weights(integ, par)

    def resid(U):
        a1 = (U - u - dt * v) / (b * dt * dt) - (1 / (2 * b) - 1) * a
        vv = v + dt * ((1 - g) * a + g * a1)
        r = (M * ((1 - am) * a1 + am * a) + M * TAU * ((1 - af) * vv + af * v)
             + KC * ((1 - af) * U + af * u) - F)
        return r, a1, vv
    r0 = resid(0.0)[0]; r1 = resid(1.0)[0]
    U = -r0 / (r1 - r0)
    _, a1, vv = resid(U)
    return np.array([X, V, U, vv, a1])


def converged_step(state, dt, *args):
    # affine map (u1, v1) -> (U, vv): find its fixed point
    base = step(state.copy(), 0.0, 0.0, dt, *args)[2:4]
    cu = step(state.copy(), 1.0, 0.0, dt, *args)[2:4] - base
    cv = step(state.copy(), 0.0, 1.0, dt, *args)[2:4] - base
    A = np.column_stack([cu, cv])
    x = np.linalg.solve(np.eye(2) - A, base)
    return step(state.copy(), x[0], x[1], dt, *args), max(abs(np.linalg.eigvals(A)))


def modes(dt, *args):
    A = np.zeros((5, 5)); rho = 0.0
    for c in range(5):
        e = np.zeros(5); e[c] = 1.0
        A[:, c], rho = converged_step(e, dt, *args)
    out = []
    for lam in sorted(np.linalg.eigvals(A), key=lambda z: -abs(z)):
        w = abs(np.angle(lam)) / dt
        if abs(lam) < 1e-12 or np.imag(lam) < -1e-12:
            continue
        z = -np.log(abs(lam)) / (dt * w) if w > 0 else float('nan')
        out.append((lam.real if abs(lam.imag) < 1e-12 else abs(lam), w, z))
    return out, rho


if __name__ == '__main__':
    C = float(sys.argv[1]) if len(sys.argv) > 1 else 5.6e3
    for dt in (3e-2, 1e-2, 1e-3):
        N = max(1, int(np.ceil(dt / DT_DEM - 1e-9)))
        print(f"dt = {dt:g} s, N = {N} DEM sub-steps, C = {C:g} N s/m")
        for wmode in ('avg', 'interp', 'end'):
            for reply in ('last', 'avg'):
                for integ, par in (('newmark', 0.0), ('bossak', -0.3), ('ga', 0.0)):
                    ms, rho = modes(dt, N, C, wmode, reply, integ, par)
                    txt = "  ".join(f"l {l:+.4f} w {w:6.1f} zeta {z:+.4f}" for l, w, z in ms[:4])
                    print(f"  wall vel {wmode:6s} reply {reply:4s} {integ:7s} {par:+.1f}  "
                          f"(fixed-point rate {rho:7.2f})  {txt}")
