#!/usr/bin/python3
"""linear_stability.py [schemes | centred | damped [C]] — stability of the CONVERGED strong
coupling step for a linear 2-dof model of cases/rest_position (paper section 7.2).

Model: sphere (253 kg) -- linear contact spring K (5.7e5 N/m, the Hertz tangent at the static
load; with `damped` also a dashpot C) -- cable node (0.66 kg, consistent-mass diagonal) --
cable spring KC (9000 N/m, gives the ~1 Hz sphere-on-cable mode) -- ground; Rayleigh C = tau M
on the node (tau 5 1/s).

DEM side: the sphere is sub-stepped with symplectic Euler, N = ceil(dt / 1.36e-3) sub-steps (the
case's automatic DEM step); in sub-step j the wall is at start + (j + off)/N (end - start):
off 1 is dem_solver's default (`net_wall.wall_position` "end"), off 0.5 is "middle", off 0 a
wall at the start of each sub-step. The reply to the FEM is 'avg' (impulse / dt, the default
`net_wall.coupling_force` "average"), 'last' (the force of the last sub-step, "end_of_step")
or 'end' (the contact force re-evaluated at the end state).
FEM side: Newmark (1/4, 1/2), Bossak (alpha_b), generalized-alpha (rho_inf); the reply is the
constant load of the step (equilibrium at t_n+1-alpha_f), or with shift = 1 the fem_solver
option `analysis.coupling_load` "step_constant" (a_n += (F_n - F_n-1) / M: the force acts over
the whole step).
The strong iteration's fixed point is solved exactly (the map is affine), so what is printed is
the time discretisation of the coupled problem, not the convergence of the iteration (except
the "fixed-point rate" of `damped`, the spectral radius of the interface map).

Studies:
  schemes   (default) where the force is valid (reply, wall offset) and the FEM integrator
            (docs/notes/rest_position.md)
  centred   the centred options step_constant + wall at the sub-step middle
            (docs/notes/centred_coupling.md)
  damped C  the contact dashpot C (default 5.6e3 N s/m: COR 0.5 at the static load) and which
            wall velocity the DEM uses (docs/notes/damped_contact.md)
Prints, per dt and scheme, |lambda| per step, frequency w [rad/s] and damping ratio zeta of the
modes (negative zeta = energy grows). Physical: slow mode ~6 rad/s zeta +0.0011, fast mode
~900 rad/s zeta ~+0.003."""
import sys
import numpy as np

MS, M, K, KC, TAU, DT_DEM = 253.0, 0.66, 5.7e5, 9000.0, 5.0, 1.36e-3


def weights(integ, par):
    """beta, gamma, alpha_m, alpha_f of Newmark, Bossak (par = alpha_b) or generalized-alpha
    (par = rho_inf, Chung & Hulbert)."""
    if integ == 'newmark':
        return 0.25, 0.5, 0.0, 0.0
    if integ == 'bossak':
        am = par
        return 0.25 * (1 - am) ** 2, 0.5 - am, am, 0.0
    rho = par
    am = (2 * rho - 1) / (rho + 1); af = rho / (rho + 1)
    return 0.25 * (1 - am + af) ** 2, 0.5 - am + af, am, af


def fem_step(u, v, a, F, dt, integ, par):
    """The cable node's implicit step under the constant load F: returns u, v, a at t_n+1."""
    b, g, am, af = weights(integ, par)

    def resid(U):
        a1 = (U - u - dt * v) / (b * dt * dt) - (1 / (2 * b) - 1) * a
        v1 = v + dt * ((1 - g) * a + g * a1)
        r = (M * ((1 - am) * a1 + am * a) + M * TAU * ((1 - af) * v1 + af * v)
             + KC * ((1 - af) * U + af * u) - F)
        return r, a1, v1
    r0 = resid(0.0)[0]; r1 = resid(1.0)[0]
    U = -r0 / (r1 - r0)
    _, a1, v1 = resid(U)
    return U, v1, a1


# ---- undamped contact: state (X, V, u, v, a, F_prev), fixed point over u_n+1 ----------------

def step(state, u1, dt, N, off, reply, integ, par, shift=0):
    """One coupling step with the end-of-step interface position u1 sent to the DEM."""
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
    U, v1, a1 = fem_step(u, v, a, F, dt, integ, par)
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


# ---- damped contact: state (X, V, u, v, a), fixed point over u_n+1 AND v_n+1 -----------------
# The DEM force on the sphere in sub-step j is K (w_j - X) + C (wdot_j - V), wall at the end of
# each sub-step; the wall velocity wdot_j is
#   'avg'    (u_n+1 - u_n) / dt in every sub-step (what dem_solver does: the received velocity
#            array is not used for the wall)
#   'interp' v_n + (j+1)/N (v_n+1 - v_n), so the last sub-step uses v_n+1
#   'end'    v_n+1 in every sub-step

def damped_step(state, u1, v1, dt, N, C, wmode, reply, integ, par):
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
    U, vv, a1 = fem_step(u, v, a, F, dt, integ, par)
    return np.array([X, V, U, vv, a1])


def damped_converged_step(state, dt, *args):
    base = damped_step(state.copy(), 0.0, 0.0, dt, *args)[2:4]
    cu = damped_step(state.copy(), 1.0, 0.0, dt, *args)[2:4] - base
    cv = damped_step(state.copy(), 0.0, 1.0, dt, *args)[2:4] - base
    A = np.column_stack([cu, cv])
    x = np.linalg.solve(np.eye(2) - A, base)
    return damped_step(state.copy(), x[0], x[1], dt, *args), max(abs(np.linalg.eigvals(A)))


def damped_modes(dt, *args):
    """Eigenvalues per step: |lambda| for complex pairs with their frequency and zeta, the signed
    value for real ones (a negative real eigenvalue is an alternating overshoot, which with a
    unilateral contact throws the node off the particle); also the interface map's rate."""
    A = np.zeros((5, 5)); rho = 0.0
    for c in range(5):
        e = np.zeros(5); e[c] = 1.0
        A[:, c], rho = damped_converged_step(e, dt, *args)
    out = []
    for lam in sorted(np.linalg.eigvals(A), key=lambda z: -abs(z)):
        w = abs(np.angle(lam)) / dt
        if abs(lam) < 1e-12 or np.imag(lam) < -1e-12:
            continue
        z = -np.log(abs(lam)) / (dt * w) if w > 0 else float('nan')
        out.append((lam.real if abs(lam.imag) < 1e-12 else abs(lam), w, z))
    return out, rho


def substeps(dt):
    return max(1, int(np.ceil(dt / DT_DEM - 1e-9)))


# ---- the three studies ------------------------------------------------------------------------

SCHEMES = [  # name, wall offset, reply, integrator, parameter
    ("wall at sub-step start, avg, Newmark", 0, 'avg', 'newmark', 0),
    ("wall at sub-step end, avg, Newmark", 1, 'avg', 'newmark', 0),
    ("wall at sub-step end, avg, Bossak -0.3  [case default]", 1, 'avg', 'bossak', -0.3),
    ("wall at sub-step end, last sub-step, Newmark", 1, 'last', 'newmark', 0),
    ("wall at sub-step end, last sub-step, Bossak -0.3  [end_of_step]", 1, 'last', 'bossak', -0.3),
    ("wall at sub-step start, end state, Bossak -0.3", 0, 'end', 'bossak', -0.3),
    ("wall at sub-step end, last sub-step, gen-alpha 0.5", 1, 'last', 'ga', 0.5),
    ("wall at sub-step end, avg, gen-alpha 1.0 (midpoint)", 1, 'avg', 'ga', 1.0),
]

CENTRED = [  # name, integrator, parameter, step_constant shift, wall offset
    ("Bossak -0.3, load at t_n+1, wall at sub-step end  [default]", 'bossak', -0.3, 0, 1.0),
    ("Bossak -0.3, step_constant, wall at sub-step end", 'bossak', -0.3, 1, 1.0),
    ("Newmark, step_constant, wall at sub-step start", 'newmark', 0.0, 1, 0.0),
    ("Newmark, step_constant, wall at sub-step middle", 'newmark', 0.0, 1, 0.5),
    ("Bossak -0.3, step_constant, wall at sub-step middle  [centred]", 'bossak', -0.3, 1, 0.5),
]


def study_schemes():
    for dt in (3e-2, 1e-2, 1e-3):
        N = substeps(dt)
        print(f"dt = {dt:g} s, N = {N} DEM sub-steps")
        for name, off, reply, integ, par in SCHEMES:
            ms = modes(dt, N, off, reply, integ, par)
            txt = "  ".join(f"|l| {l:.4f} w {w:6.1f} zeta {z:+.4f}" for l, w, z in ms[:2])
            print(f"  {name:62s} {txt}")


def study_centred():
    for dt in (3e-2, 1e-2, 5e-3, 2.5e-3, 2e-3, 1e-3, 2.5e-4):
        N = substeps(dt)
        print(f"dt = {dt:g} s, N = {N} DEM sub-steps")
        for name, integ, par, shift, off in CENTRED:
            ms = modes(dt, N, off, 'avg', integ, par, shift)
            print(f"  {name:62s} " + "  ".join(f"|l| {l:.4f} w {w:6.1f} zeta {z:+.4f}"
                                               for l, w, z in ms[:2]))


def study_damped(C):
    for dt in (3e-2, 1e-2, 1e-3):
        N = substeps(dt)
        print(f"dt = {dt:g} s, N = {N} DEM sub-steps, C = {C:g} N s/m")
        for wmode in ('avg', 'interp', 'end'):
            for reply in ('last', 'avg'):
                for integ, par in (('newmark', 0.0), ('bossak', -0.3), ('ga', 0.0)):
                    ms, rho = damped_modes(dt, N, C, wmode, reply, integ, par)
                    txt = "  ".join(f"l {l:+.4f} w {w:6.1f} zeta {z:+.4f}" for l, w, z in ms[:4])
                    print(f"  wall vel {wmode:6s} reply {reply:4s} {integ:7s} {par:+.1f}  "
                          f"(fixed-point rate {rho:7.2f})  {txt}")


if __name__ == '__main__':
    which = sys.argv[1] if len(sys.argv) > 1 else 'schemes'
    if which == 'schemes':
        study_schemes()
    elif which == 'centred':
        study_centred()
    elif which == 'damped':
        study_damped(float(sys.argv[2]) if len(sys.argv) > 2 else 5.6e3)
    else:
        sys.exit(f"linear_stability.py: unknown study '{which}' (schemes, centred, damped [C])")
