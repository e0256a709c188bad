"""contact_steps — what the end-to-end tests of the compliance options read from a run.

measure(tmp, names, node, component, switch) -> {name: dict(avg, mx, on, peak)} for the
results folders tmp/<name>: the interface iterations per contact step (a step any of whose
tries touched; every try counted) on average and at most, from coupling.h5 /iterations;
`on`, coupling.h5's attribute `switch` times `interface_compliance` (whether that option
acted); and the peak |displacement| of monitor node `node` along `component`, as
scripts/study.py reads the terrain cases. Prints one line per run."""
import h5py
import numpy as np

import nc_results


def measure(tmp, names, node, component, switch):
    r = {}
    for name in names:
        d = "%s/%s" % (tmp, name)
        with h5py.File(d + "/coupling.h5", "r") as f:
            step = np.array(f["/iterations/step"]).astype(int).ravel()
            touched = np.linalg.norm(np.array(f["/iterations/contact_force"]), axis=1) > 0
            counts = np.bincount(step)
            contact = np.unique(step[touched])
            on = float(f.attrs[switch]) * float(f.attrs["interface_compliance"])
        r[name] = dict(avg=float(counts[contact].mean()), mx=int(counts[contact].max()), on=on,
                       peak=float(np.abs(nc_results.load_monitor(d).node(node, component)).max()))
        print("%-9s %.2f iterations per contact step, at most %d (every try counted), peak %.5f m"
              % (name, r[name]["avg"], r[name]["mx"], r[name]["peak"]))
    return r
