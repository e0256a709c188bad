#!/usr/bin/python3
"""steps_detail.py RUN_DIR T0 T1 — every coupling step between T0 and T1: node 1/2 z displacement
and velocity (fem.h5 monitor), sphere z, vz, gap of the sphere centre to the edge 1-2 midpoint,
total DEM force on the net (dem.h5 /net/force, z), coupler contact force and iterations."""
import sys, os, h5py, numpy as np
d, t0, t1 = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
fem = h5py.File(os.path.join(d, 'fem.h5'), 'r')
t = fem['/monitor/time'][:]; u = fem['/monitor/displacement'][:]; v = fem['/monitor/velocity'][:]
dem = h5py.File(os.path.join(d, 'dem.h5'), 'r')
tdem = dem['time'][:]
P = dem['particles/position'][:]; V = dem['particles/velocity'][:]
NP = dem['net/position'][:] if 'net/position' in dem else None
NF = dem['net/force'][:] if 'net/force' in dem else None
n0 = int(dem['net'].attrs['first_output_step']) if 'net' in dem else 0
cpl = h5py.File(os.path.join(d, 'coupling.h5'), 'r')
ct = cpl['steps/time'][:]; it = cpl['steps/iterations'][:]; cf = cpl['steps/contact_force'][:]
print("    t      u1z      u2z      v1z      v2z    sph_z    sph_vz  c-edge   Fnet_z(dem)  Fz(cpl)  it")
for i, ti in enumerate(t):
    if ti < t0 - 1e-9 or ti > t1 + 1e-9: continue
    j = int(np.argmin(abs(tdem - ti)))
    pz = P[j, 0, 2]; vz = V[j, 0, 2]
    has_net = NF is not None and 0 <= j - n0 < len(NF)
    nf = NF[j - n0].sum(axis=0)[2] if has_net else np.nan
    npz = NP[j - n0] if has_net else None
    mid = 0.5 * (npz[1, 2] + npz[2, 2]) if npz is not None else 0.5 * (u[i, 0, 2] + u[i, 1, 2])
    k = int(np.argmin(abs(ct - ti)))
    flag = '' if abs(tdem[j] - ti) < 1e-6 else f' (dem t {tdem[j]:.4f})'
    print(f"{ti:7.4f} {u[i,0,2]:8.4f} {u[i,1,2]:8.4f} {v[i,0,2]:8.3f} {v[i,1,2]:8.3f} {pz:8.4f} {vz:8.3f} "
          f"{pz-mid:7.4f} {nf:11.1f} {cf[k,2]:9.1f} {it[k]:3d}{flag}")
