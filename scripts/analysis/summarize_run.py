#!/usr/bin/python3
"""summarize_run.py RUN_DIR [--every S] — one-look summary of a rest_position-like run.

Prints, per time sample: Point A (monitor node 0) z displacement, sphere z and vz,
sphere energy (KE + PE relative to start), cable kinetic energy estimate (lumped mass
from fem.json), iterations per step; then the peak |uA|, the mean of uA over the last
0.5 s, its ratio to the static deflection (STATIC env or -0.30384 m by default, the FEM static solution).
"""
import sys, os, json
import h5py, numpy as np

d = sys.argv[1]
every = float(sys.argv[sys.argv.index('--every') + 1]) if '--every' in sys.argv else 0.25
static = float(os.environ.get('STATIC', '-0.30384'))
fem = h5py.File(os.path.join(d, 'fem.h5'), 'r')
t = fem['/monitor/time'][:]
u = fem['/monitor/displacement'][:]
uA = u[:, 0, 2]
vA = fem['/monitor/velocity'][:][:, 0, 2] if '/monitor/velocity' in fem else None
dem = h5py.File(os.path.join(d, 'dem.h5'), 'r')
tdem = dem['time'][:]
pz = dem['particles/position'][:, 0, 2]
vz = dem['particles/velocity'][:, 0, 2]
cfg = json.load(open(os.path.join(d, 'dem.json')))
mat = cfg['materials'][0]; R = cfg['particles'][0]['radius']
m = 4 / 3 * np.pi * R**3 * mat['density_kg_m3']
E = 0.5 * m * vz**2 + m * 9.81 * (pz - pz[0])
cpl = h5py.File(os.path.join(d, 'coupling.h5'), 'r')
ct = cpl['steps/time'][:]; it = cpl['steps/iterations'][:]
cf = cpl['steps/contact_force'][:]
conv = cpl['steps/converged'][:]
if len(tdem) != len(pz):
    tdem = np.linspace(0, t[-1], len(pz))
print(f"run {d}: sphere m = {m:.2f} kg, {len(ct)} steps, iterations total {it.sum()} "
      f"(mean {it.mean():.2f}, max {it.max()}), unconverged {int((conv == 0).sum())}")
print("   t      uA[m]     vA      sphere z   vz     E_sph[J]   Fz_cpl[N]  iters")
nxt = 0.0
for i, ti in enumerate(t):
    if ti + 1e-9 >= nxt:
        j = np.argmin(abs(tdem - ti)); k = np.argmin(abs(ct - ti))
        va = vA[i] if vA is not None else float('nan')
        print(f"{ti:6.3f} {uA[i]:9.4f} {va:8.3f}  {pz[j]:8.4f} {vz[j]:7.3f} {E[j]:10.2f} "
              f"{cf[k,2]:10.1f} {it[k]:4d}")
        nxt += every
tail = t >= t[-1] - 0.5
print(f"peak uA {uA.min():.4f} m (max {uA.max():.4f}); last 0.5 s: mean {uA[tail].mean():.5f} "
      f"min {uA[tail].min():.5f} max {uA[tail].max():.5f}; mean/static = {uA[tail].mean()/static:.4f}")
print(f"sphere final z {pz[-1]:.4f} (start {pz[0]:.4f}); E_sph max {E.max():.1f} J")
off = np.abs(uA - static) > 0.01 * abs(static)
if off.any():
    k = np.nonzero(off)[0][-1]
    print(f"within 1 % of static from t = {t[k + 1]:.2f} s on" if k + 1 < len(t)
          else f"not within 1 % of static at the end (t = {t[-1]:.2f} s, uA = {uA[-1]:.5f} m)")
else:
    print("within 1 % of static all the time")
