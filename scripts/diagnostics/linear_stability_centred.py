#!/usr/bin/env python3
"""linear_stability_centred.py — linear_stability.py's 2-dof model of case 7.2 (253 kg sphere,
contact spring, 0.66 kg cable node, cable spring, Rayleigh tau 5) with the two options of
centred_coupling.md: the FEM shifting its start-of-step acceleration by (F_n - F_n-1)/M so the
step's force acts over the whole step (fem_solver analysis.coupling_load "step_constant") and
the DEM wall at the middle of each sub-step (off 0.5, dem_solver net_wall.wall_position
"middle"; off 1 = "end", the default). The DEM reply is the step average (impulse/dt).
Prints, per dt and scheme, |lambda| per step, frequency and damping ratio zeta of the two modes
(negative zeta = energy grows). Physical: slow mode 5.9 rad/s zeta +0.0011, fast mode ~930
rad/s zeta ~+0.0026."""
import os, sys
import numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import linear_stability as L  # noqa: E402
MS, M, K, KC, TAU, DT_DEM = L.MS, L.M, L.K, L.KC, L.TAU, L.DT_DEM
def step(state, u1, dt, N, off, integ, par, shift):
    X, V, u, v, a, Fp = state
    h = dt / N; imp = 0.0
    for j in range(N):
        w = u + (j + off) / N * (u1 - u)
        f = K * (w - X)
        V += h * f / MS; X += h * V
        imp -= h * f
    F = imp / dt
    if shift: a = a + (F - Fp) / M
    b, g, am, af = L.weights(integ, par)
    def resid(U):
        a1 = (U - u - dt * v) / (b * dt * dt) - (1 / (2 * b) - 1) * a
        v1 = v + dt * ((1 - g) * a + g * a1)
        r = M * ((1 - am) * a1 + am * a) + M * TAU * ((1 - af) * v1 + af * v) + KC * ((1 - af) * U + af * u) - F
        return r, a1, v1
    r0 = resid(0.0)[0]; r1 = resid(1.0)[0]
    U = -r0 / (r1 - r0)
    _, a1, v1 = resid(U)
    return np.array([X, V, U, v1, a1, F])
def converged(state, dt, *args):
    s0 = step(state.copy(), 0.0, dt, *args)[2]
    s1 = step(state.copy(), 1.0, dt, *args)[2]
    u1 = s0 / (1 - (s1 - s0))
    return step(state.copy(), u1, dt, *args)
def modes(dt, *args):
    A = np.zeros((6, 6))
    for c in range(6):
        e = np.zeros(6); e[c] = 1.0
        A[:, c] = converged(e, dt, *args)
    out = []
    for lam in sorted(np.linalg.eigvals(A), key=lambda z: -abs(z)):
        w = abs(np.angle(lam)) / dt
        if abs(lam) < 1e-9 or w == 0 or np.imag(lam) < 0: continue
        out.append((abs(lam), w, -np.log(abs(lam)) / (dt * w)))
    return out
SCHEMES = [("Bossak -0.3, load at t_n+1, wall at sub-step end  [default]", 'bossak', -0.3, 0, 1.0),
           ("Bossak -0.3, step_constant, wall at sub-step end", 'bossak', -0.3, 1, 1.0),
           ("Newmark, step_constant, wall at sub-step start", 'newmark', 0.0, 1, 0.0),
           ("Newmark, step_constant, wall at sub-step middle", 'newmark', 0.0, 1, 0.5),
           ("Bossak -0.3, step_constant, wall at sub-step middle  [centred]", 'bossak', -0.3, 1, 0.5)]
if __name__ == "__main__":
    for dt in (3e-2, 1e-2, 5e-3, 2.5e-3, 2e-3, 1e-3, 2.5e-4):
        N = max(1, int(np.ceil(dt / DT_DEM - 1e-9)))
        print(f"dt = {dt:g} s, N = {N} DEM sub-steps")
        for name, integ, par, shift, off in SCHEMES:
            ms = modes(dt, N, off, integ, par, shift)
            print(f"  {name:62s} " + "  ".join(f"|l| {l:.4f} w {w:6.1f} zeta {z:+.4f}" for l, w, z in ms[:2]))
