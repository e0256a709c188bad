#!/usr/bin/python3
"""energy.py RUN_DIR [T0 T1] — energy bookkeeping of a rest_position run, per output sample:
sphere KE + gravity PE (dem.h5), cable KE (consistent or lumped mass, from fem.h5 monitor
velocities of nodes 1 and 2, which are all free nodes of this case) + strain energy above the
prestressed state, Hertz contact energy from the sphere-edge(1-2) overlap, their total, and the
energy dissipated by Rayleigh damping so far (integral of tau v^T M v dt). Total + dissipated
should never rise above its start value (0) by more than the integration error; a rise is
energy created by the scheme. Prints the largest rise and where it happens. The dissipation is
integrated from 0.01 s samples: with a cable chattering at the Nyquist frequency of the coupling
step it is overestimated, so the mechanical total alone (printed too) is the safer indicator."""
import sys, os, json, math
import h5py, numpy as np
d = sys.argv[1]
t0 = float(sys.argv[2]) if len(sys.argv) > 2 else 0.0
t1 = float(sys.argv[3]) if len(sys.argv) > 3 else 1e9
fj = json.load(open(os.path.join(d, 'fem.json'))); dj = json.load(open(os.path.join(d, 'dem.json')))
es = fj['element_sets'][0]
E, A, rho, Spre = es['youngs_modulus_pa'], es['area_m2'], es['density_kg_m3'], es['prestress_pa']
tau = fj.get('rayleigh', {}).get('tau_per_s', 0.0)
lumped = fj.get('mass', 'consistent') == 'lumped'
m_el = rho * A * 1.0
Mn = np.diag([m_el, m_el]) if lumped else np.array([[2 * m_el / 3, m_el / 6], [m_el / 6, 2 * m_el / 3]])
mat = dj['materials'][0]; R = dj['particles'][0]['radius']; z0 = dj['particles'][0]['position'][2]
Ms = 4 / 3 * math.pi * R**3 * mat['density_kg_m3']
nw = dj['net_wall']
Estar = 1 / ((1 - mat['poisson_ratio']**2) / mat['youngs_modulus_pa'] + (1 - nw['poisson_ratio']**2) / nw['youngs_modulus_pa'])
f = h5py.File(os.path.join(d, 'fem.h5'), 'r')
t = f['/monitor/time'][:]; u = f['/monitor/displacement'][:]; v = f['/monitor/velocity'][:]
X = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], float)
def cable(ui, vi):
    U = np.zeros((4, 3)); U[1:3] = ui
    ke = 0.5 * sum(vi[:, c] @ Mn @ vi[:, c] for c in range(3))
    w = 0.0
    for k, l in [(0, 1), (1, 2), (2, 3)]:
        dd = X[l] + U[l] - X[k] - U[k]; l2 = dd @ dd
        AS = max(E * A * (l2 - 1) / 2 + A * Spre, 0.0)
        w += (AS * AS - (A * Spre)**2) / (2 * E * A)
    return ke, w, 2 * tau * ke  # dissipation rate tau v^T M v = 2 tau KE
g = h5py.File(os.path.join(d, 'dem.h5'), 'r')
td = g['time'][:]; P = g['particles/position'][:]; V = g['particles/velocity'][:]
rows = []
diss = 0.0; prev_rate = None; prev_t = None
for i, ti in enumerate(t):
    ke, w, rate = cable(u[i], v[i])
    if prev_rate is not None: diss += 0.5 * (rate + prev_rate) * (ti - prev_t)
    prev_rate, prev_t = rate, ti
    j = int(np.argmin(abs(td - ti)))
    if abs(td[j] - ti) > 1e-6: continue
    p = P[j, 0]; vs = V[j, 0]
    es_ = 0.5 * Ms * vs @ vs + Ms * 9.81 * (p[2] - z0)
    a = X[1] + np.r_[u[i, 0]]; b = X[2] + u[i, 1]
    ab = b - a; tt = np.clip((p - a) @ ab / (ab @ ab), 0, 1); q = a + tt * ab
    ov = max(R - np.linalg.norm(q - p), 0.0)
    ec = 8 / 15 * Estar * math.sqrt(R) * ov**2.5
    rows.append((ti, es_, ke, w, ec, es_ + ke + w + ec, diss))
rows = np.array(rows)
tot = rows[:, 5] + rows[:, 6]
print("    t     E_sphere   KE_cable  W_cable   E_contact   total   +dissipated")
for r, tt_ in zip(rows, tot):
    if t0 <= r[0] <= t1:
        print(f"{r[0]:7.3f} {r[1]:10.2f} {r[2]:9.2f} {r[3]:9.2f} {r[4]:9.2f} {r[5]:9.2f} {tt_:9.2f}")
km = int(np.argmax(rows[:, 5]))
print(f"max of mechanical total (no dissipation credit): {rows[km,5]:.2f} J at t = {rows[km,0]:.3f} s; "
      f"final {rows[-1,5]:.2f} J")
k = int(np.argmax(tot))
jumps = np.diff(tot); kj = int(np.argmax(jumps))
print(f"max of total+dissipated: {tot[k]:.2f} J at t = {rows[k,0]:.3f} s (start {tot[0]:.2f}); "
      f"largest single-sample rise {jumps[kj]:.2f} J at t = {rows[kj+1,0]:.3f} s; final {tot[-1]:.2f} J")
