#!/usr/bin/env python3
"""linear_stability.py — amplification matrix of the CONVERGED strong coupling step for a linear
2-dof model of case 7.2: sphere (253 kg) -- linear contact spring k (5.7e5 N/m, the Hertz tangent
at the static load) -- cable node (0.66 kg, consistent-mass diagonal) -- cable spring kc (9000 N/m,
gives the ~1 Hz sphere-on-cable mode) -- ground; Rayleigh C = tau M on the node (tau 5).

DEM: the sphere is sub-stepped with symplectic Euler (N = ceil(dt / 1.36e-3) sub-steps, the auto
DEM step of the case); in sub-step j the wall is at start + (j + off)/N (end - start): off = 0 is
the DEM of 23:55 (wall at the start of each sub-step), off = 1 the current one (wall at the end).
Reply to the FEM: 'avg' impulse/dt (protocol default), 'end' contact force of the end state
(sphere and wall at their end positions), 'last' the force of the last sub-step.
FEM: Newmark (1/4, 1/2), Bossak (alpha_b), generalized-alpha (rho_inf), the reply used as the
constant load of the step (equilibrium at t_n+1-alpha_f).
The strong iteration's fixed point is solved exactly (the map is affine). Prints, per scheme,
the modes: |lambda| per step, frequency and equivalent damping ratio zeta (negative = energy
grows). Physical: slow mode ~6 rad/s zeta ~0.0011, fast mode ~900 rad/s zeta ~0.003."""
import numpy as np

MS, M, K, KC, TAU, DT_DEM = 253.0, 0.66, 5.7e5, 9000.0, 5.0, 1.36e-3


def weights(integ, par):
    if integ == 'newmark':
        return 0.25, 0.5, 0.0, 0.0
    if integ == 'bossak':
        am = par
        return 0.25 * (1 - am) ** 2, 0.5 - am, am, 0.0
    rho = par  # generalized alpha, Chung & Hulbert
    am = (2 * rho - 1) / (rho + 1); af = rho / (rho + 1)
    return 0.25 * (1 - am + af) ** 2, 0.5 - am + af, am, af


def step(state, u1, dt, N, off, reply, integ, par, shift=0):
    """One coupling step; state = (X, V, u, v, a, F_prev). shift = 1: the FEM's
    coupling_load "step_constant" (a_n += (F - F_prev) / M, the force acts over the whole step)."""
    X, V, u, v, a, Fp = state
    h = dt / N; imp = 0.0; flast = 0.0
    for j in range(N):
        w = u + (j + off) / N * (u1 - u)
        f = K * (w - X)            # on the sphere (linear, bilateral)
        V += h * f / MS; X += h * V
        imp -= h * f; flast = -f
    F = {'avg': imp / dt, 'end': -K * (u1 - X), 'last': flast}[reply]
    if shift:
        a = a + (F - Fp) / M
    b, g, am, af = weights(integ, par)

    def resid(U):
        a1 = (U - u - dt * v) / (b * dt * dt) - (1 / (2 * b) - 1) * a
        v1 = v + dt * ((1 - g) * a + g * a1)
        r = M * ((1 - am) * a1 + am * a) + M * TAU * ((1 - af) * v1 + af * v) + KC * ((1 - af) * U + af * u) - F
        return r, a1, v1
    r0 = resid(0.0)[0]; r1 = resid(1.0)[0]
    U = -r0 / (r1 - r0)
    _, a1, v1 = resid(U)
    return np.array([X, V, U, v1, a1, F])


def converged_step(state, dt, *args):
    s0 = step(state.copy(), 0.0, dt, *args)[2]
    s1 = step(state.copy(), 1.0, dt, *args)[2]
    u1 = s0 / (1 - (s1 - s0))       # fixed point of u1 -> FEM(DEM(u1))
    return step(state.copy(), u1, dt, *args)


def modes(dt, *args):
    A = np.zeros((6, 6))
    for c in range(6):
        e = np.zeros(6); e[c] = 1.0
        A[:, c] = converged_step(e, dt, *args)
    out = []
    for lam in sorted(np.linalg.eigvals(A), key=lambda z: -abs(z)):
        w = abs(np.angle(lam)) / dt
        if abs(lam) < 1e-9 or w == 0 or np.imag(lam) < 0:
            continue
        out.append((abs(lam), w, -np.log(abs(lam)) / (dt * w)))
    return out


SCHEMES = [
    ("23:55 DEM (off 0), avg, Newmark  [original]", 0, 'avg', 'newmark', 0),
    ("current DEM (off 1), avg, Newmark", 1, 'avg', 'newmark', 0),
    ("current DEM (off 1), avg, Bossak -0.3  [case now]", 1, 'avg', 'bossak', -0.3),
    ("current DEM (off 1), last sub-step, Newmark", 1, 'last', 'newmark', 0),
    ("current DEM (off 1), last sub-step, Bossak -0.3  [patch]", 1, 'last', 'bossak', -0.3),
    ("23:55 DEM (off 0), end state, Bossak -0.3", 0, 'end', 'bossak', -0.3),
    ("current DEM (off 1), last sub-step, gen-alpha 0.5", 1, 'last', 'ga', 0.5),
    ("current DEM (off 1), avg, gen-alpha 1.0 (midpoint)", 1, 'avg', 'ga', 1.0),
]
if __name__ == '__main__':
    for dt in (3e-2, 1e-2, 1e-3):
        N = max(1, int(np.ceil(dt / DT_DEM - 1e-9)))
        print(f"dt = {dt:g} s, N = {N} DEM sub-steps")
        for name, off, reply, integ, par in SCHEMES:
            ms = modes(dt, N, off, reply, integ, par)
            txt = "  ".join(f"|l| {l:.4f} w {w:6.1f} zeta {z:+.4f}" for l, w, z in ms[:2])
            print(f"  {name:58s} {txt}")
