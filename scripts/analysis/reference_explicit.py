#!/usr/bin/python3
"""reference_explicit.py [T_END] [DT] [COR] [--mass consistent|lumped] [--tau TAU] [--save FILE.npz] — independent fine-step reference
for paper case 7.2 (no coupling, no sub-stepping): the 3-element prestressed cable (E 1e9, A 1.26e-4,
rho 7850, S_pre 1e6, Rayleigh C = tau M, tau 5) and the sphere (R 0.12, rho 3.5e4, E 1e7, nu 0.2, COR)
integrated together with one explicit central-difference / symplectic-Euler step of DT (default 2e-5 s,
far below the contact period ~7 ms and the axial period ~12 ms). Hertz normal contact on the segment
1-2 with the damping fit of eqs. (A.8)–(A.10) and the tangent-stiffness dashpot, as dem_solver does.
Prints Point A (node 1) z, sphere z, energies every 0.1 s and the mean of the last 0.5 s.
--save FILE.npz: every step's t, uA (node 1 z), sphere z and vz, contact force on the net (z), for
contact_intervals.py and the tests (docs/notes/damped_contact.md: contact loss, time to rest).
--case cable_impact [--swap x]: paper 7.1 instead (cases/cable_impact; contact still only on the
inner element 1-2); --swap x takes outer E 1e9 / inner 1e5 (the case's reading).
Options that take a value (--mass, --tau, --save, --case, --swap) must be given one."""
import sys, math
import numpy as np
args = []
skip = False
for a in sys.argv[1:]:
    if skip: skip = False; continue
    if a.startswith('--'): skip = True; continue
    args.append(a)
T = float(args[0]) if len(args) > 0 else 4.0
dt = float(args[1]) if len(args) > 1 else 2e-5
cor = float(args[2]) if len(args) > 2 else 1.0
lumped = '--mass' in sys.argv and sys.argv[sys.argv.index('--mass') + 1] == 'lumped'
tau_arg = float(sys.argv[sys.argv.index('--tau') + 1]) if '--tau' in sys.argv else 5.0
save = sys.argv[sys.argv.index('--save') + 1] if '--save' in sys.argv else None
E, A, rho, Spre, tau = 1e9, 1.26e-4, 7850.0, 1e6, tau_arg
R, rhos, Es, nus = 0.12, 3.5e4, 1e7, 0.2
Eel = [E, E, E]; z0 = 0.42
if '--case' in sys.argv and sys.argv[sys.argv.index('--case') + 1] == 'cable_impact':
    # paper 7.1 (cases/cable_impact): E outer 1e5 / inner 1e9 (--swap: outer 1e9 / inner 1e5),
    # S_pre 1e4, sphere R 0.4, rho 2e4, lowest point 0.30 m above the cable
    Eel = [1e9, 1e5, 1e9] if '--swap' in sys.argv else [1e5, 1e9, 1e5]
    Spre = 1e4; R, rhos = 0.4, 2e4; z0 = 0.70
Ew, nuw = 2.1e11, 0.3
g = 9.81
Ms = 4 / 3 * math.pi * R**3 * rhos
Estar = 1 / ((1 - nus**2) / Es + (1 - nuw**2) / Ew)
h = [-6.918798, -16.41105, 146.8049, -796.4559, 2928.711, -7206.864, 11494.29, -11342.18, 6276.757, -1489.915]
def zeta_fit(e):
    e = min(max(e, 0.001), 1.0)
    if e > 0.999: return 0.0
    # eq. (A.9), nested Horner form: e*(h1 + e*(h2 + ... + e*h10))
    lam = h[-1]
    for c in reversed(h[:-1]): lam = c + e * lam
    lam *= e
    return math.sqrt(1 / (1 - (1 + e)**2 * math.exp(lam)) - 1)
zeta = zeta_fit(cor)
X = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], float)
els = [(0, 1), (1, 2), (2, 3)]
L0 = 1.0
m_el = rho * A * L0
# mass matrix of the free dofs (nodes 1, 2), per direction (2x2)
if lumped:
    Mn = np.diag([m_el, m_el])
else:
    Mn = np.array([[2 * m_el / 3, m_el / 6], [m_el / 6, 2 * m_el / 3]])
Minv = np.linalg.inv(Mn)
u = np.zeros((4, 3)); v = np.zeros((4, 3))
xs = np.array([1.5, 0.0, z0]); vs = np.zeros(3)
def internal(u):
    f = np.zeros((4, 3))
    for ie, (k, l) in enumerate(els):
        d = X[l] + u[l] - X[k] - u[k]
        l2 = d @ d
        S = Eel[ie] * (l2 - L0 * L0) / (2 * L0 * L0) + Spre
        if S < 0: continue
        fl = A * S / L0 * d
        f[l] += fl; f[k] -= fl
    return f
def contact(u, v, xs, vs):
    a = X[1] + u[1]; b = X[2] + u[2]
    ab = b - a; t = np.clip((xs - a) @ ab / (ab @ ab), 0, 1)
    q = a + t * ab
    dvec = q - xs; dist = math.sqrt(dvec @ dvec)
    fnode = np.zeros((4, 3))
    if dist >= R: return np.zeros(3), fnode, 0.0
    n = dvec / dist; ov = R - dist
    vw = (1 - t) * v[1] + t * v[2]
    vn = (vw - vs) @ n
    kt = 2 * Estar * math.sqrt(R * ov)
    fn = 2 / 3 * kt * ov + 2 * zeta * math.sqrt(Ms * kt) * (-vn)
    fn = max(fn, 0.0)
    fsph = -fn * n
    fnode[1] = (1 - t) * fn * n; fnode[2] = t * fn * n
    return fsph, fnode, ov
nsteps = int(round(T / dt)); every = int(round(0.1 / dt))
hist = []
print("    t      uA       sphere_z   vz     E_sphere   E_cable    E_total (rel. start)")
for it in range(nsteps + 1):
    t = it * dt
    fint = internal(u)
    fsph, fnode, ov = contact(u, v, xs, vs)
    if it % every == 0 or it == nsteps:
        Ekc = 0.5 * sum(v[[1, 2], c] @ Mn @ v[[1, 2], c] for c in range(3))
        Wc = 0.0
        for ie, (k, l) in enumerate(els):
            d = X[l] + u[l] - X[k] - u[k]; l2 = d @ d
            AS = Eel[ie] * A * (l2 - 1) / 2 + A * Spre
            AS = max(AS, 0.0)
            Wc += L0 * (AS * AS - (A * Spre)**2) / (2 * Eel[ie] * A)
        Es_ = 0.5 * Ms * vs @ vs + Ms * g * (xs[2] - z0)
        Ec = 8 / 15 * Estar * math.sqrt(R) * ov**2.5
        print(f"{t:6.2f} {u[1,2]:8.4f}  {xs[2]:8.4f} {vs[2]:7.3f} {Es_:9.2f} {Ekc+Wc:9.2f} {Es_+Ekc+Wc+Ec:9.2f}")
    hist.append((t, u[1, 2], xs[2], vs[2], fnode[1, 2] + fnode[2, 2]))
    if it == nsteps: break
    # free nodes 1, 2: M a = f_contact - f_int - tau M v
    for c in range(3):
        rhs = np.array([fnode[1, c] - fint[1, c], fnode[2, c] - fint[2, c]])
        acc = Minv @ rhs - tau * v[[1, 2], c]
        v[1, c] += dt * acc[0]; v[2, c] += dt * acc[1]
    u[1] += dt * v[1]; u[2] += dt * v[2]
    vs += dt * (fsph / Ms + np.array([0, 0, -g]))
    xs += dt * vs
hist = np.array(hist)
if save:
    np.savez(save, t=hist[:, 0], uA=hist[:, 1], zs=hist[:, 2], vzs=hist[:, 3], fz=hist[:, 4])
tail = hist[hist[:, 0] >= T - 0.5, 1]
print(f"last 0.5 s: uA mean {tail.mean():.5f} min {tail.min():.5f} max {tail.max():.5f}; peak uA {hist[:,1].min():.4f}")
