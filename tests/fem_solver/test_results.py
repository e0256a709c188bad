"""fem.h5 holds what a designer asks for, checked on a static steel net (3 m x 3 m, 21 x 21
nodes, ropes E 1e11 Pa, A 5e-5 m2, prestress 2e7 Pa, self-weight, a 20 kN rock load at the
centre and an oblique 5 kN point load):

- the support reactions balance the applied loads at every load step: sum(R) + lambda * (self-
  weight + point loads) = 0 within 1e-6 of the load (Newton's residual tolerance is 1e-10
  relative; the reactions are computed independently of the solver's residual, from element
  forces), and R is 0 on dofs that are not supported;
- /output/strain equals (l - L0) / L0 recomputed from /output/position and the mesh;
- the run's largest |u| (attributes of /output/displacement) is the maximum over the monitored
  steps, with its time and node;
- every dataset carries a "units" attribute, and the summary line names the maximum's node.
"""
import json
import os
import subprocess
import sys

import h5py
import numpy as np

root = os.environ.get("NC_ROOT", os.getcwd())
bin_dir = os.environ.get("NC_BIN", os.path.join(root, "bin"))
tmp = os.environ.get("NC_TMP", "results/test_tmp")
os.makedirs(tmp, exist_ok=True)

E, A, RHO, S_PRE, G = 1e11, 5e-5, 7850.0, 2e7, 9.81
model = {
    "description": "static steel net for the reaction balance",
    "net": {"origin_m": [0, 0, 0], "edge1_m": [3, 0, 0], "edge2_m": [0, 3, 0],
            "count1": 21, "count2": 21, "set": "net"},
    "element_sets": [{"name": "net", "youngs_modulus_pa": E, "area_m2": A, "density_kg_m3": RHO,
                      "prestress_pa": S_PRE, "behaviour": "cable"}],
    "supports": [{"nodes": "boundary", "dofs": "xyz"}],
    "self_weight": True,
    "gravity_m_s2": [0, 0, -G],
    "point_loads": [{"nodes": "center", "force_n": [0, 0, -20000]},
                    {"nodes": [115], "force_n": [3000, -1000, -4000]}],
    "monitor_nodes": ["center"],
    "output": {"interval_steps": 1},
    "analysis": {"type": "static", "load_steps": 8},
}
path = os.path.join(tmp, "static_net.json")
with open(path, "w") as f:
    json.dump(model, f)
out = os.path.join(tmp, "static_net")
run = subprocess.run([os.path.join(bin_dir, "fem_solver"), path, "--output", out],
                     capture_output=True, text=True)
if run.returncode != 0:
    sys.exit("fem_solver failed: %s" % run.stderr)
failures = []

with h5py.File(os.path.join(out, "fem.h5"), "r") as f:
    X = f["/mesh/coordinates"][:]
    conn = f["/mesh/elements"][:]
    L0 = f["/mesh/reference_length"][:]
    sup = f["/mesh/support_nodes"][:]
    sup_dofs = f["/mesh/support_dofs"][:]
    lam = f["/output/load_factor"][:]
    R = f["/output/reaction"][:]
    pos = f["/output/position"][:]
    strain = f["/output/strain"][:]
    disp = f["/output/displacement"]
    max_u, max_t, max_node = (disp.attrs[k] for k in ("max_magnitude", "max_time", "max_node"))
    mon_t = f["/monitor/time"][:]
    u_all = disp[:]
    missing = []
    f.visititems(lambda name, obj: missing.append(name)
                 if isinstance(obj, h5py.Dataset) and "units" not in obj.attrs else None)
    if missing:
        failures.append("datasets without a units attribute: %s" % missing)

# the applied load at full scale, computed here from the model (not read from the solver)
weight = RHO * A * np.linalg.norm(X[conn[:, 1]] - X[conn[:, 0]], axis=1).sum() * G
applied = np.array([3000.0, -1000.0, -20000.0 - 4000.0 - weight])
scale = np.linalg.norm(applied)
for k in range(len(lam)):
    total = R[k].sum(axis=0) + lam[k] * applied
    if np.abs(total).max() > 1e-6 * scale:
        failures.append("step %d (load factor %g): reactions + loads = %s N (allowed %.3g N)"
                        % (k, lam[k], total, 1e-6 * scale))
if np.abs(R[:, sup_dofs == 0]).max(initial=0.0) != 0.0:
    failures.append("reaction on a free dof")
if len(sup) != 80 or not (sup_dofs == 1).all():
    failures.append("expected the 80 boundary nodes fully supported, got %d" % len(sup))
if not np.isclose(lam[-1], 1.0) or abs(R[-1].sum(axis=0)[2] - (24000.0 + weight)) > 1e-6 * scale:
    failures.append("final vertical reaction %.6f N, expected %.6f N" % (R[-1].sum(axis=0)[2], 24000.0 + weight))

length = np.linalg.norm(pos[:, conn[:, 1]] - pos[:, conn[:, 0]], axis=2)
ref = (length - L0) / L0
if np.abs(strain - ref).max() > 1e-12:
    failures.append("strain differs from (l - L0)/L0 by %.3g" % np.abs(strain - ref).max())
if strain[-1].max() <= 0:
    failures.append("a loaded net should stretch")

mag = np.linalg.norm(u_all, axis=2)
k, node = np.unravel_index(np.argmax(mag), mag.shape)
if abs(max_u - mag[k, node]) > 1e-15 or int(max_node) != node or max_t != mon_t[-1]:
    failures.append("max |u| attributes %g at %g node %d, expected %g at %g node %d"
                    % (max_u, max_t, max_node, mag[k, node], mon_t[-1], node))
if "node %d" % node not in run.stderr:
    failures.append("summary does not name the node of max |u|: %s" % run.stderr.strip())

for msg in failures:
    print("FAIL:", msg)
if failures:
    sys.exit(1)
print("reactions balance the loads (%.1f N) at %d load steps; strains, max |u| and units ok"
      % (scale, len(lam)))
