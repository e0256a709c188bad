#!/usr/bin/python3
"""Plots of one coupled run: monitor-node deflection, largest rope force and the support
reactions over time, contact force, interface iterations, and the contact force over the
iterations of the step that needed the most.

    scripts/plot_results.py RESULTS_DIR [--out DIR] [--node ID] [--component z]
"""
import argparse
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import nc_results  # noqa: E402

COMPONENTS = {"x": 0, "y": 1, "z": 2}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("results")
    parser.add_argument("--out", help="folder for the PNG files (default: RESULTS/plots)")
    parser.add_argument("--node", type=int, action="append", help="monitor node id (default: all)")
    parser.add_argument("--component", default="z", choices=COMPONENTS)
    parser.add_argument("--static", help="results folder of a static FEM solve to draw as reference")
    args = parser.parse_args()
    out = args.out or os.path.join(args.results, "plots")
    os.makedirs(out, exist_ok=True)
    c = COMPONENTS[args.component]
    written = []

    monitor = nc_results.load_monitor(args.results)
    fig, ax = plt.subplots(figsize=(7, 4))
    for node in args.node or monitor.node_ids:
        ax.plot(monitor.time, monitor.node(node, c), label="node %d" % node)
    if args.static:
        static = nc_results.load_monitor(args.static)
        for node in args.node or monitor.node_ids:
            if node in static.node_ids:
                value = static.node(node, c)[-1]
                ax.axhline(value, ls="--", color="k", lw=1)
                ax.annotate("static, node %d: %.4g m" % (node, value), (monitor.time[0], value),
                            textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("displacement %s [m]" % args.component)
    ax.grid(True, alpha=0.3)
    ax.legend()
    path = os.path.join(out, "monitor_displacement.png")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    written.append(path)

    fem = nc_results.load_fem(args.results)
    if len(fem.time):
        fig, axes = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
        axes[0].plot(fem.time, fem.axial_force.max(axis=1) / 1e3)
        axes[0].set_ylabel("largest axial force [kN]")
        axes[0].grid(True, alpha=0.3)
        for i, node in enumerate(fem.support_nodes):
            axes[1].plot(fem.time, np.linalg.norm(fem.reaction[:, i], axis=1) / 1e3, label="node %d" % node)
        axes[1].set_ylabel("support reaction |R| [kN]")
        axes[1].set_xlabel("time [s]")
        axes[1].grid(True, alpha=0.3)
        if len(fem.support_nodes) <= 8:
            axes[1].legend(fontsize=8)
        path = os.path.join(out, "forces_reactions.png")
        fig.tight_layout()
        fig.savefig(path, dpi=120)
        written.append(path)

    coupling_path = os.path.join(args.results, "coupling.h5")
    if os.path.exists(coupling_path):
        cp = nc_results.Coupling(coupling_path)
        fig, axes = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
        axes[0].plot(cp.end_time, cp.force_magnitude())
        axes[0].set_ylabel("contact force on the net [N]")
        axes[0].grid(True, alpha=0.3)
        axes[1].step(cp.end_time, cp.iterations, where="post")
        axes[1].set_ylabel("interface iterations")
        axes[1].set_xlabel("time [s]")
        axes[1].grid(True, alpha=0.3)
        path = os.path.join(out, "coupling_history.png")
        fig.tight_layout()
        fig.savefig(path, dpi=120)
        written.append(path)

        if len(cp.iterations) and cp.iterations.max() > 1:
            step = int(np.argmax(cp.iterations))
            its, force = cp.iterations_of_step(step)
            fig, ax = plt.subplots(figsize=(6, 4))
            ax.plot(its, force, "o-")
            ax.set_xlabel("interface iteration")
            ax.set_ylabel("contact force [N]")
            ax.set_title("step %d (t = %.4g s)" % (step, cp.end_time[step]))
            ax.grid(True, alpha=0.3)
            path = os.path.join(out, "iteration_force.png")
            fig.tight_layout()
            fig.savefig(path, dpi=120)
            written.append(path)
    for p in written:
        print(p)


if __name__ == "__main__":
    main()
