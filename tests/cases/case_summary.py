#!/usr/bin/python3
"""case_summary.py RUN_DIR [--every S] — print what a coupled case run did, from its HDF5 files.

Per sphere: start/end position and velocity (dem.h5); monitored FEM nodes: min/max/final
displacement (fem.h5 /monitor); coupling: iterations per step (mean, max), unconverged steps,
steps in contact, wall time (coupling.h5). Used by the case READMEs and tests/cases/test_*.sh
(import it: `from case_summary import load`)."""
import sys
import h5py
import numpy as np


def load(run):
    """Return a dict of numpy arrays read from RUN/dem.h5, fem.h5, coupling.h5."""
    r = {}
    with h5py.File(run + "/dem.h5", "r") as f:
        r["t"] = f["/time"][:]
        r["pos"] = np.array(f["/particles/position"])
        r["vel"] = np.array(f["/particles/velocity"])
        r["radius"] = f["/particles/radius"][:]
        r["body"] = f["/particles/body"][:]
        if "/clusters/position" in f:
            r["cpos"] = np.array(f["/clusters/position"])
        r["ekin"] = f["/energy/kinetic"][:]
    with h5py.File(run + "/fem.h5", "r") as f:
        r["mt"] = f["/monitor/time"][:]
        r["mid"] = f["/monitor/node_ids"][:]
        r["mu"] = f["/monitor/displacement"][:]
        r["fem_t"] = f["/output/time"][:]
        r["fem_u"] = f["/output/displacement"][:]
        r["coords"] = f["/mesh/coordinates"][:]
    with h5py.File(run + "/coupling.h5", "r") as f:
        r["ct"] = f["/steps/time"][:]
        r["it"] = f["/steps/iterations"][:]
        r["conv"] = f["/steps/converged"][:]
        r["inc"] = f["/steps/in_contact"][:]
        r["cf"] = f["/steps/contact_force"][:]
        r["wall"] = float(f["/timing/total"][0])
    return r


def main():
    run = sys.argv[1]
    every = float(sys.argv[sys.argv.index("--every") + 1]) if "--every" in sys.argv else None
    r = load(run)
    np.set_printoptions(precision=4, suppress=True)
    print("run %s: %d coupling steps to t = %.4f s, wall %.2f s" % (run, len(r["ct"]), r["ct"][-1], r["wall"]))
    it = r["it"]
    print("iterations/step: mean %.2f, max %d; unconverged %d; steps in contact %d"
          % (it.mean(), it.max(), int((r["conv"] == 0).sum()), int(r["inc"].sum())))
    if r["inc"].any():
        i = np.nonzero(r["inc"])[0]
        print("contact from t = %.4f to %.4f s; iterations in contact steps mean %.2f"
              % (r["ct"][i[0]], r["ct"][i[-1]], it[i].mean()))
        gap, longest = 0, 0
        for c in r["inc"][i[0]:]:
            gap = 0 if c else gap + 1
            longest = max(longest, gap)
        print("after first contact: %d of %d steps without contact, longest gap %d steps"
              % (int((r["inc"][i[0]:] == 0).sum()), len(r["inc"]) - i[0], longest))
    for p in range(r["pos"].shape[1]):
        print("sphere %d (R %.3f, body %d): start %s end %s, v end %s |v| %.3f"
              % (p, r["radius"][p], r["body"][p], r["pos"][0, p], r["pos"][-1, p], r["vel"][-1, p],
                 np.linalg.norm(r["vel"][-1, p])))
    if "cpos" in r:
        for c in range(r["cpos"].shape[1]):
            print("cluster %d: start %s end %s, min z %.4f at t %.3f"
                  % (c, r["cpos"][0, c], r["cpos"][-1, c], r["cpos"][:, c, 2].min(), r["t"][r["cpos"][:, c, 2].argmin()]))
    for j, n in enumerate(r["mid"]):
        u = r["mu"][:, j, :]
        k = np.argmin(u[:, 2])
        print("node %d %s: min u_z %.4f m at t %.4f, final u %s" % (n, r["coords"][n], u[k, 2], r["mt"][k], u[-1]))
    uz = r["fem_u"][:, :, 2]
    print("net: min u_z over all nodes and outputs %.4f m" % uz.min())
    if every:
        nxt = 0.0
        for k, t in enumerate(r["t"]):
            if t + 1e-12 >= nxt:
                j = np.argmin(abs(r["mt"] - t))
                print("t %.4f  x0 %s v0 %s  u_mon %s" % (t, r["pos"][k, 0], r["vel"][k, 0], r["mu"][j, 0]))
                nxt += every


if __name__ == "__main__":
    main()
