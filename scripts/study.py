#!/usr/bin/python3
"""Parameter studies of the paper (section 7) and their figures.

    scripts/study.py STUDY [--out DIR] [--jobs N] [--end-time T]
    scripts/study.py --list

Each study runs a case several times through scripts/run_case.sh with --set overrides (no
copied case folders), at most N runs at a time (default 2, one per core), then draws the
paper's figure(s) as PNG into DIR/STUDY/ and prints a summary table. Runs already finished
in DIR are reused, so an interrupted study continues where it stopped; a run is reused only
when its stamp (the contents of the programs, the launcher and the case's input files, and
the --set list) is the one it would have now, else it is run again (delete DIR/STUDY to
start afresh). --end-time shortens every run (quick looks, tests).
"""
import argparse
import concurrent.futures
import functools
import hashlib
import json
import os
import shutil
import signal
import statistics
import subprocess
import sys
import textwrap
import time

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import nc_results  # noqa: E402

POINT_A = 1  # node at x = 1 m in the cable cases
PROGRAMS = ("coupler", "fem_solver", "dem_solver", "netcouple-set")  # what run_case.sh runs


# what a case folder holds besides its inputs: documentation changes no result
CASE_DOCS = (".md", ".png")


def _digest_files(paths):
    """sha256 over (name, contents) of each (name, path): names, not paths, so the same
    programs in another folder ($NC_BIN) give the same digest."""
    h = hashlib.sha256()
    for name, path in paths:
        h.update(name.encode() + b"\0")
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
    return h.hexdigest()


@functools.lru_cache(maxsize=None)
def code_digest(case):
    """Digest of what a run of `case` computes with: the programs (from $NC_BIN, as
    run_case.sh takes them), the launcher and the case folder's input files."""
    bin_dir = os.environ.get("NC_BIN", os.path.join(ROOT, "bin"))
    paths = [(p, os.path.join(bin_dir, p)) for p in PROGRAMS]
    paths.append(("run_case.sh", os.path.join(HERE, "run_case.sh")))
    case_dir = os.path.join(ROOT, "cases", case)
    for folder, dirs, files in os.walk(case_dir):
        dirs.sort()
        paths += [(os.path.relpath(os.path.join(folder, name), case_dir), os.path.join(folder, name))
                  for name in sorted(files) if not name.endswith(CASE_DOCS)]
    missing = [path for _, path in paths if not os.path.isfile(path)]
    if missing:
        sys.exit("study: %s not found (build with make, or set NC_BIN)" % missing[0])
    return _digest_files(paths)


def stale_reason(info, stamp):
    """Why finished results with done.json `info` may not be reused for `stamp`, or None."""
    old = info.get("stamp")
    if not old:
        return "no stamp (results of an older study script)"
    if old.get("sets") != stamp["sets"]:
        return "other --set options"
    if old.get("code") != stamp["code"]:
        return "the programs, the launcher or the case's inputs changed"
    if info.get("timed_out") and old.get("timeout_s") != stamp["timeout_s"]:
        return "it was stopped at another wall-time cap"
    return None


def run(case, label, sets, out_dir, end_time=None, timeout_s=None):
    """Runs one case variant unless its results are complete and stamped with the same
    programs, case folder and --set options; returns (label, dir, seconds, ok).
    timeout_s: wall-time cap; a run still going then is stopped like Ctrl-C (the coupler shuts
    the solvers down, coupling.h5 keeps the steps done) and recorded as timed out."""
    run_dir = os.path.join(out_dir, label)
    done = os.path.join(run_dir, "done.json")
    all_sets = sets + (["coupler.end_time=%g" % end_time] if end_time else [])
    stamp = {"sets": all_sets, "timeout_s": timeout_s, "code": code_digest(case)}
    if os.path.exists(done):
        with open(done) as f:
            info = json.load(f)
        reason = stale_reason(info, stamp)
        if reason is None:
            return label, run_dir, info["seconds"], info["ok"]
        print("  %-28s run again: %s" % (label, reason))
        shutil.rmtree(run_dir)
    args = [os.path.join(HERE, "run_case.sh"), os.path.join(ROOT, "cases", case), "--out", run_dir, "--quiet"]
    for s in all_sets:
        args += ["--set", s]
    start = time.monotonic()
    timed_out = False
    # its own process group: a capped run's leftovers can be ended without touching others
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)
    try:
        output, _ = proc.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        timed_out = True
        proc.send_signal(signal.SIGTERM)  # run_case.sh interrupts the coupler, which shuts down the solvers
        try:
            output, _ = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            output, _ = proc.communicate()
    seconds = time.monotonic() - start
    ok = proc.returncode == 0 and not timed_out
    os.makedirs(run_dir, exist_ok=True)
    with open(os.path.join(run_dir, "study.log"), "w") as f:
        f.write(output)
    with open(done, "w") as f:
        json.dump({"seconds": seconds, "ok": ok, "sets": sets, "returncode": proc.returncode,
                   "timed_out": timed_out, "stamp": stamp}, f)
    return label, run_dir, seconds, ok


def run_all(case, variants, out_dir, jobs, end_time, timeout_s=None):
    os.makedirs(out_dir, exist_ok=True)
    if jobs > 1:
        # several coupled runs share the cores: OpenBLAS's own threads (CHOLMOD in fem_solver)
        # then fight the other runs' processes; on a three-module barrier beside another run
        # the FEM's factorisations took 3.3-6.5 s with two threads, 0.8-0.9 s with one (alone:
        # 0.9-1.0 s with two, 1.4-2.7 s with one, so a single run keeps the default)
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    results = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = [pool.submit(run, case, label, sets, out_dir, end_time, timeout_s) for label, sets in variants]
        for future in concurrent.futures.as_completed(futures):
            label, run_dir, seconds, ok = future.result()
            print("  %-28s %6.1f s  %s" % (label, seconds, "ok" if ok else "FAILED (see %s)" % run_dir))
            results[label] = (run_dir, seconds, ok)
    return results


def static_solution(case, out_dir):
    """Point A of the FEM static solve for the particle's weight (eq. (43))."""
    static_dir = os.path.join(out_dir, "static")
    stamp_path = os.path.join(static_dir, "stamp.json")
    stamp = {"code": code_digest(case)}
    try:
        with open(stamp_path) as f:
            fresh = json.load(f) == stamp and os.path.exists(os.path.join(static_dir, "fem.h5"))
    except (OSError, ValueError):
        fresh = False
    if not fresh:
        shutil.rmtree(static_dir, ignore_errors=True)
        os.makedirs(static_dir, exist_ok=True)
        binary = os.path.join(os.environ.get("NC_BIN", os.path.join(ROOT, "bin")), "fem_solver")
        subprocess.run([binary, os.path.join(ROOT, "cases", case, "static.json"), "--output", static_dir],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with open(stamp_path, "w") as f:
            json.dump(stamp, f)
    return nc_results.load_monitor(static_dir).node(POINT_A)[-1]


def save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    print("  wrote", path)


def plot_runs(results, labels, path, title, ylabel, draw, reference=None):
    """One curve per run: draw(ax, run_dir, label) plots it (runs without results are left
    out); reference: (value, label) drawn as a dashed horizontal line."""
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for label in labels:
        run_dir, _, ok = results[label]
        try:
            draw(ax, run_dir, label + ("" if ok else " (failed)"))
        except (OSError, KeyError):
            continue
    if reference is not None:
        ax.axhline(reference[0], color="k", ls="--", lw=1, label=reference[1])
    ax.set_xlabel("time [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    save(fig, path)


def plot_point_a(results, labels, path, title, static=None):
    def draw(ax, run_dir, label):
        m = nc_results.load_monitor(run_dir)
        ax.plot(m.time, m.node(POINT_A), label=label, lw=1)
    plot_runs(results, labels, path, title, "Point A vertical displacement [m]", draw,
              None if static is None else (static, "static (eq. (43))"))


def plot_iterations(results, labels, path, title):
    def draw(ax, run_dir, label):
        c = nc_results.load_coupling(run_dir)
        ax.step(c.end_time, c.iterations, where="pre", label=label, lw=1)  # value of step (t - dt, t]
    plot_runs(results, labels, path, title, "interface iterations per step", draw)


def summary(results, labels, static=None):
    print("  %-28s %8s %10s %10s %12s %12s" % ("run", "wall[s]", "steps", "iterations", "A at end[m]", "A min[m]"))
    rows = {}
    for label in labels:
        run_dir, seconds, ok = results[label]
        try:
            c = nc_results.load_coupling(run_dir)
            m = nc_results.load_monitor(run_dir)
            a = m.node(POINT_A)
            rows[label] = dict(seconds=seconds, steps=len(c.iterations), iterations=c.total_iterations(),
                               a_end=float(a[-1]), a_min=float(a.min()), ok=ok,
                               unconverged=int((c.converged == 0).sum()))
            print("  %-28s %8.1f %10d %10d %12.4f %12.4f%s" % (
                label, seconds, len(c.iterations), c.total_iterations(), a[-1], a.min(),
                "" if ok else "  FAILED"))
        except (OSError, KeyError) as e:
            print("  %-28s no results (%s)" % (label, e))
    if static is not None:
        print("  static Point A: %.4f m" % static)
    return rows


# ---- the studies -------------------------------------------------------------------------

def study_timestep(out, jobs, end_time):
    """7.2, fig. 12 and 13: weak vs strong at several dt against the static solution."""
    variants = [("weak_dt1e-3", ["coupler.scheme=weak", "coupler.dt=1e-3"]),
                ("weak_dt1e-2", ["coupler.scheme=weak", "coupler.dt=1e-2"]),
                ("strong_dt1e-2", ["coupler.scheme=strong", "coupler.dt=1e-2"]),
                ("strong_dt3e-2", ["coupler.scheme=strong", "coupler.dt=3e-2"]),
                ("strong_dt1e-2_force", ["coupler.scheme=strong", "coupler.dt=1e-2",
                                         "coupler.relaxed_quantity=force"]),
                ("strong_dt3e-2_force", ["coupler.scheme=strong", "coupler.dt=3e-2",
                                         "coupler.relaxed_quantity=force"])]
    results = run_all("rest_position", variants, out, jobs, end_time)
    static = static_solution("rest_position", out)
    labels = [v[0] for v in variants]
    plot_point_a(results, labels[:4], os.path.join(out, "fig12_point_a_vs_static.png"),
                 "rest position (7.2): weak and strong coupling vs the static solution", static)
    plot_iterations(results, ["strong_dt1e-2", "strong_dt3e-2"], os.path.join(out, "fig13a_iterations_displacement.png"),
                    "interface iterations, relaxed displacements and velocities")
    plot_iterations(results, ["strong_dt1e-2_force", "strong_dt3e-2_force"],
                    os.path.join(out, "fig13b_iterations_force.png"), "interface iterations, relaxed forces")
    summary(results, labels, static)


# 7.3's coupling step. The paper gives none for this study. The interface map's gain grows with
# the step (contact stiffness times the cable node's compliance over the step, ~ k_c dt^2 / m), so
# which constant factors converge depends on it: at 1e-3 even alpha = 1.0 converges, at 5e-3 and
# 1e-2 alpha = 0.5 and 0.7 fail too (study relaxation_dt). 2.5e-3 is a step at which the paper's
# finding holds: every alpha < 1 converges, alpha = 1.0 does not.
RELAXATION_DT = "2.5e-3"
# COR 1 isolates the relaxation (paper 7.3); 200 iterations per step let alpha = 0.1 converge
# everywhere; a step that still has not converged is accepted and counted (column "unconverged")
# at the study's fixed dt (no step rejection: relaxation_variant sets step_control.dt_min = dt);
# the paper's iteration, without the contact backtracking (docs/notes/contact_backtracking.md)
RELAXATION_COMMON = ["dem.materials.0.restitution=1.0", "coupler.on_max_iterations=accept",
                     "coupler.max_iterations=200", "coupler.accept_unconverged=true",
                     "coupler.contact_backtracking=0"]


def relaxation_variant(alpha, dt):
    method = (["coupler.relaxation.method=aitken"] if alpha == "aitken" else
              ["coupler.relaxation.method=constant", "coupler.relaxation.alpha=" + alpha])
    return method + ["coupler.dt=" + dt, "coupler.step_control.dt_min=" + dt] + RELAXATION_COMMON


def study_relaxation(out, jobs, end_time):
    """7.3, Table 1 and fig. 14: constant alpha vs Aitken (displacement relaxation, COR 1, dt 2.5e-3)."""
    alphas = ["0.1", "0.2", "0.5", "0.7", "1.0", "aitken"]
    variants = [("aitken" if a == "aitken" else "alpha_" + a, relaxation_variant(a, RELAXATION_DT)) for a in alphas]
    results = run_all("rest_position", variants, out, jobs, end_time)
    static = static_solution("rest_position", out)
    labels = [v[0] for v in variants]
    plot_point_a(results, labels, os.path.join(out, "fig14_relaxation.png"),
                 "relaxation factor (7.3), strong, dt %s s, COR 1" % RELAXATION_DT, static)
    rows = summary(results, labels, static)
    base = rows.get("alpha_0.1")
    print("\n  Table 1 — computation time relative to alpha = 0.1 (paper: 100, 54.1, 20.4, 28.5, -, Aitken 18.7)")
    print("  %-12s %14s %14s %14s" % ("relaxation", "time [%]", "iterations [%]", "unconverged"))
    for label in labels:
        r = rows.get(label)
        if r and base:
            print("  %-12s %14.1f %14.1f %14d" % (label, 100 * r["seconds"] / base["seconds"],
                                                   100 * r["iterations"] / base["iterations"], r["unconverged"]))


def study_relaxation_dt(out, jobs, end_time):
    """7.3 at several dt: which constant alpha converge depends on the coupling step (1 s runs)."""
    dts = ["1e-3", "2.5e-3", "5e-3", "1e-2"]
    alphas = ["0.5", "0.7", "1.0", "aitken"]
    variants = [("dt%s_%s" % (dt, a), relaxation_variant(a, dt)) for dt in dts for a in alphas]
    results = run_all("rest_position", variants, out, jobs, end_time or 1.0)
    print("\n  unconverged steps (of all steps) and total interface iterations, first 1 s, COR 1")
    print("  %-8s" % "dt [s]" + "".join("%22s" % ("alpha " + a if a != "aitken" else "Aitken") for a in alphas))
    for dt in dts:
        cells = []
        for a in alphas:
            run_dir, _, ok = results["dt%s_%s" % (dt, a)]
            try:
                c = nc_results.load_coupling(run_dir)
                cells.append("%4d/%-5d %7d it" % ((c.converged == 0).sum(), len(c.iterations), c.total_iterations()))
            except (OSError, KeyError):
                cells.append("no results")
        print("  %-8s" % dt + "".join("%22s" % cell for cell in cells))


def study_restitution(out, jobs, end_time):
    """7.4, fig. 16 and 17: COR sweep, weak (dt 1e-3, 4 s) and strong (dt 3e-2, 8 s: long enough to come to rest)."""
    cors = ["1.0", "0.8", "0.5", "0.2", "0.1"]
    settings = {"weak": ["coupler.scheme=weak", "coupler.dt=1e-3", "fem.analysis.dt_s=1e-3"],
                "strong": ["coupler.scheme=strong", "coupler.dt=3e-2", "fem.analysis.dt_s=3e-2",
                           "coupler.end_time=8", "fem.analysis.end_time_s=8"]}
    variants = []
    for scheme in ("weak", "strong"):
        for cor in cors:
            variants.append(("%s_cor%s" % (scheme, cor), settings[scheme] + ["dem.materials.0.restitution=" + cor]))
    results = run_all("rest_position", variants, out, jobs, end_time)
    static = static_solution("rest_position", out)
    plot_point_a(results, ["weak_cor" + c for c in cors], os.path.join(out, "fig16a_weak_cor.png"),
                 "coefficient of restitution (7.4), weak coupling", static)
    plot_point_a(results, ["strong_cor" + c for c in cors], os.path.join(out, "fig16b_strong_cor.png"),
                 "coefficient of restitution (7.4), strong coupling", static)
    plot_iterations(results, ["strong_cor" + c for c in cors], os.path.join(out, "fig17_iterations_cor.png"),
                    "interface iterations per step (7.4)")
    summary(results, [v[0] for v in variants], static)


def study_cable_impact(out, jobs, end_time):
    """7.1, fig. 9 and 11: weak at 2e-4, 1e-3 and 1e-2, strong at 1e-2."""
    # weak 2e-4: the largest step measured to work here (the paper: 1e-3; README)
    variants = [("weak_dt2e-4", ["coupler.scheme=weak", "coupler.dt=2e-4"]),
                ("weak_dt1e-3", ["coupler.scheme=weak", "coupler.dt=1e-3"]),
                ("weak_dt1e-2", ["coupler.scheme=weak", "coupler.dt=1e-2"]),
                ("strong_dt1e-2", ["coupler.scheme=strong", "coupler.dt=1e-2"])]
    results = run_all("cable_impact", variants, out, jobs, end_time)
    labels = [v[0] for v in variants]
    plot_point_a(results, labels, os.path.join(out, "fig9_point_a.png"), "impact on a compliant cable (7.1)")
    run_dir = results["strong_dt1e-2"][0]
    try:
        c = nc_results.load_coupling(run_dir)
        fig, axes = plt.subplots(1, 2, figsize=(11, 4))
        contact_steps = np.where(c.iterations > 1)[0]
        if len(contact_steps):
            step = int(contact_steps[np.argmax(c.iterations[contact_steps])])
            its, force = c.iterations_of_step(step)
            axes[0].plot(its, force, "o-")
            axes[0].set_title("contact force over the iterations of step %d (t = %.3g s)" % (step, c.end_time[step]))
            axes[0].set_xlabel("interface iteration")
            axes[0].set_ylabel("contact force [N]")
            axes[0].grid(True, alpha=0.3)
            print("  first-iteration force / converged force at that step: %.2f" % (force[0] / max(force[-1], 1e-30)))
        axes[1].step(c.end_time, c.iterations, where="pre")
        axes[1].set_xlabel("time [s]")
        axes[1].set_ylabel("interface iterations per step")
        axes[1].grid(True, alpha=0.3)
        save(fig, os.path.join(out, "fig11_iterations.png"))
    except (OSError, KeyError) as e:
        print("  no coupling history for fig. 11:", e)
    for label in labels:
        try:
            c = nc_results.load_coupling(results[label][0])
            print("  %-16s contact lost and regained: %s" % (label, nc_results.contact_lost_and_regained(c)))
        except (OSError, KeyError):
            pass
    summary(results, labels)


CENTRE_NODE = 220  # cases/angled_net: node at the origin, monitored (fem.json node set "center")


def study_angled_net(out, jobs, end_time):
    """7.5, fig. 20: angled net, weak 5e-5 / 1e-4 / 2e-4, strong 2e-4, centre node and iterations.
    The weak runs are the paper's plain exchange (no interface Jacobian), as
    tests/cases/test_angled_net.sh; weak 2e-4 creates energy and is let run to the end."""
    plain = ["coupler.scheme=weak", "coupler.interface_jacobian=false"]
    variants = [("weak_dt5e-5", plain + ["coupler.dt=5e-5", "fem.analysis.dt_s=5e-5"]),
                ("weak_dt1e-4", plain + ["coupler.dt=1e-4", "fem.analysis.dt_s=1e-4"]),
                ("weak_dt2e-4", plain + ["coupler.dt=2e-4", "fem.analysis.dt_s=2e-4",
                                         "coupler.accept_energy_growth=true"]),
                ("strong_dt2e-4", ["coupler.scheme=strong", "coupler.dt=2e-4", "fem.analysis.dt_s=2e-4"])]
    results = run_all("angled_net", variants, out, jobs, end_time)
    labels = [v[0] for v in variants]
    curves, rows = {}, {}
    for label in labels:
        run_dir, seconds, ok = results[label]
        try:
            m = nc_results.load_monitor(run_dir)
            c = nc_results.load_coupling(run_dir)
        except (OSError, KeyError) as e:
            print("  %-16s no results (%s)" % (label, e))
            continue
        curves[label] = (m.time, m.node(CENTRE_NODE), c)
        rows[label] = dict(seconds=seconds, ok=ok, c=c)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    styles = {"weak_dt5e-5": dict(color="tab:gray", lw=2.5, alpha=0.6),
              "weak_dt1e-4": dict(color="k", lw=1.2), "weak_dt2e-4": dict(color="tab:red", lw=1, ls="--"),
              "strong_dt2e-4": dict(color="tab:blue", lw=1.2, ls="-.")}
    lows = []
    for label, (t, u, _) in curves.items():
        axes[0].plot(t, u, label=label.replace("_dt", " ") + ("" if rows[label]["ok"] else " (failed)"),
                     **styles[label])
        if label != "weak_dt2e-4":
            lows.append(u.min())
    if lows:
        # weak 2e-4 is flung off the rock (metres); keep the axis on the other two, as fig. 20a
        axes[0].set_ylim(1.5 * min(lows), 0.1)
    if "weak_dt2e-4" in curves:
        t, u, _ = curves["weak_dt2e-4"]
        axes[0].annotate("weak 2e-4 leaves the axis (min %.2f m):\ncontact lost, net flung off" % u.min(),
                         xy=(0.02, 0.04), xycoords="axes fraction", fontsize=8, color="tab:red")
    axes[0].set_xlabel("time [s]")
    axes[0].set_ylabel("centre node vertical displacement [m]")
    axes[0].set_title("(a) centre node (node %d)" % CENTRE_NODE)
    axes[0].grid(True, alpha=0.3)
    axes[0].legend(fontsize=8, loc="lower left", bbox_to_anchor=(0, 0.1))
    if "strong_dt2e-4" in curves:
        c = curves["strong_dt2e-4"][2]
        axes[1].step(c.end_time, c.iterations, where="pre", color="tab:blue", lw=0.8)
    axes[1].set_xlabel("time [s]")
    axes[1].set_ylabel("interface iterations per step")
    axes[1].set_title("(b) strong coupling, dt = 2e-4 s (weak: 1 per step)")
    axes[1].grid(True, alpha=0.3)
    fig.suptitle("angled protection net (7.5, fig. 20)")
    save(fig, os.path.join(out, "fig20_angled_net.png"))
    print("  %-16s %8s %8s %14s %14s %10s %8s %12s" % ("run", "wall[s]", "steps", "centre min[m]", "centre end[m]",
                                                      "it/step", "max it", "unconverged"))
    for label in labels:
        if label not in curves:
            continue
        t, u, c = curves[label]
        # weak coupling does one exchange per step: its converged flag says nothing
        unconverged = "-" if label.startswith("weak") else str(int((c.converged == 0).sum()))
        print("  %-16s %8.1f %8d %14.4f %14.4f %10.2f %8d %12s%s" % (
            label, rows[label]["seconds"], len(c.iterations), u.min(), u[-1], c.iterations.mean(),
            c.iterations.max(), unconverged, "" if rows[label]["ok"] else "  FAILED"))
    for ref in ("weak_dt5e-5", "weak_dt1e-4"):
        if ref not in curves:
            continue
        t1, u1, _ = curves[ref]
        peak = np.abs(u1).max()
        for label in ("strong_dt2e-4", "weak_dt1e-4", "weak_dt2e-4"):
            if label in curves and label != ref:
                t, u, _ = curves[label]
                diff = np.abs(u - np.interp(t, t1, u1)).max()
                print("  max |%s - %s| at the centre node: %.4f m (%.1f %% of the peak %.3f m)"
                      % (label, ref, diff, 100 * diff / peak, peak))



# ---- 7.6 / 7.7: terrain, curtain, cluster, sieve (one run each, the cases as they are) ------

def load_run(case, run_dir):
    """(dem, fem, monitor, coupling) of a finished run, or None (reported) when it has none."""
    try:
        return (load_dem(run_dir), load_fem_output(run_dir), nc_results.load_monitor(run_dir),
                nc_results.load_coupling(run_dir))
    except (OSError, KeyError) as e:
        print("  %-16s no results (%s)" % (case, e))
        return None


def load_dem(run_dir):
    """Sphere (and cluster) positions of dem.h5: time [k], position [k, p, 3], velocity, radius."""
    import h5py
    r = {}
    with h5py.File(os.path.join(run_dir, "dem.h5"), "r") as f:
        r["t"] = np.array(f["/time"])
        r["pos"] = np.array(f["/particles/position"])
        r["vel"] = np.array(f["/particles/velocity"])
        r["radius"] = np.array(f["/particles/radius"])
        if "/clusters/position" in f:
            r["cpos"] = np.array(f["/clusters/position"])
    return r


def load_fem_output(run_dir):
    """FEM output steps: time [k], displacement [k, n, 3], reference coordinates [n, 3], element sets."""
    import h5py
    with h5py.File(os.path.join(run_dir, "fem.h5"), "r") as f:
        return dict(t=np.array(f["/output/time"]), u=np.array(f["/output/displacement"]),
                    x=np.array(f["/mesh/coordinates"]), elements=np.array(f["/mesh/elements"]),
                    element_set=np.array(f["/mesh/element_set"]))


def terrain_section(stl_path, y0=0.0):
    """Terrain profile z(x) at y = y0 from the case's STL (its grid has vertices on y = 0)."""
    pts = {}
    with open(stl_path) as f:
        for line in f:
            w = line.split()
            if w and w[0] == "vertex" and abs(float(w[2]) - y0) < 1e-6:
                pts[round(float(w[1]), 6)] = float(w[3])
    xs = np.array(sorted(pts))
    return xs, np.array([pts[x] for x in xs])


def max_deflection(fem, nodes):
    """Largest displacement magnitude among NODES at every FEM output step."""
    return np.linalg.norm(fem["u"][:, nodes, :], axis=2).max(axis=1)


def section_nodes(fem, axis, value, nodes=None, tol=1e-6):
    """Nodes whose reference coordinate AXIS equals VALUE (a line of the net), optionally among NODES."""
    idx = np.nonzero(np.abs(fem["x"][:, axis] - value) < tol)[0]
    if nodes is not None:
        idx = np.intersect1d(idx, nodes)
    return idx


def contact_spans(ax, run_dir, **kw):
    """Shades the coupling steps in contact on AX."""
    c = nc_results.load_coupling(run_dir)
    for t0, t1 in nc_results.contact_intervals(c.start_time, c.end_time, c.in_contact.astype(float), 0.5):
        ax.axvspan(t0, t1, **kw)
    return c


def _terrain_case_figure(case, run_dir, ok, path, title):
    """x-z path of the rock over the terrain section y = 0 and the net(s) at the largest
    deflection; max net deflection over time. Returns the numbers printed in the summary."""
    dem, fem = load_dem(run_dir), load_fem_output(run_dir)
    tx, tz = terrain_section(os.path.join(ROOT, "cases", case, "terrain.stl"))
    c = nc_results.load_coupling(run_dir)
    sets = {}
    for e, s in zip(fem["elements"], fem["element_set"]):
        sets.setdefault(int(s), set()).update(int(n) for n in e)
    sets = {s: np.array(sorted(n)) for s, n in sets.items()}
    # the protection net is the structure at x = 6 m, the curtain (if any) the other one
    structures = {}
    for s, nodes in sets.items():
        name = "protection net" if np.allclose(fem["x"][nodes, 0], 6.0) else "curtain"
        structures[name] = nodes
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.8), gridspec_kw=dict(width_ratios=[1.5, 1]))
    ax = axes[0]
    ax.fill_between(tx, tz, -0.5, color="0.85", lw=0)
    ax.plot(tx, tz, color="0.4", lw=1, label="terrain (STL section y = 0)")
    p = dem["pos"][:, 0, :]
    R = dem["radius"][0]
    ax.plot(p[:, 0], p[:, 2], color="tab:brown", lw=1.2, label="rock centre (R %.2f m)" % R)
    k_max = int(np.argmax(p[:, 0]))
    ax.add_patch(plt.Circle((p[k_max, 0], p[k_max, 2]), R, fill=False, color="tab:brown", ls="--"))
    ax.plot(p[0, 0], p[0, 2], "o", color="tab:brown", ms=4)
    numbers = dict(x_max=p[k_max, 0], t_x_max=dem["t"][k_max],
                   iterations=c.iterations.mean(), it_max=int(c.iterations.max()),
                   unconverged=int((c.converged == 0).sum()), ok=ok, end=dem["t"][-1])
    colours = {"protection net": "tab:blue", "curtain": "tab:green"}
    right = axes[1]
    for name, nodes in sorted(structures.items()):
        d = max_deflection(fem, nodes)
        k = int(np.argmax(d))
        line = section_nodes(fem, 1, 0.0, nodes)
        line = line[np.argsort(fem["x"][line, 2])]
        x0 = fem["x"][line]
        ax.plot(x0[:, 0], x0[:, 2], color=colours[name], lw=1, ls=":", label=name + " (y = 0), at rest")
        xd = x0 + fem["u"][k, line, :]
        ax.plot(xd[:, 0], xd[:, 2], color=colours[name], lw=1.5,
                label="%s at t = %.2f s (largest deflection)" % (name, fem["t"][k]))
        right.plot(fem["t"], d, color=colours[name], lw=1.2, label=name + ": max |u| over its nodes")
        numbers[name] = (d[k], fem["t"][k])
    ax.set_aspect("equal")
    ax.set_xlim(-0.3, 7.0)
    ax.set_ylim(-0.3, 3.2)
    ax.set_xlabel("x [m] (downhill)")
    ax.set_ylabel("z [m]")
    ax.set_title("(a) rock path (x-z) and nets, section y = 0")
    ax.legend(fontsize=7, loc="upper right")
    ax.grid(True, alpha=0.3)
    for t0, t1 in nc_results.contact_intervals(c.start_time, c.end_time, c.in_contact.astype(float), 0.5):
        right.axvspan(t0, t1, color="tab:orange", alpha=0.25, lw=0)
    right.plot([], [], color="tab:orange", alpha=0.4, lw=6, label="rock in contact with a net")
    right.set_xlabel("time [s]")
    right.set_ylabel("largest net displacement [m]")
    right.set_title("(b) net deflection over time")
    right.grid(True, alpha=0.3)
    right.legend(fontsize=7, loc="upper right")
    fig.suptitle(title)
    save(fig, path)
    return numbers


def study_terrain(out, jobs, end_time):
    """7.6, figs. 21-22: rock rolling down an STL terrain into a net (terrain_net, terrain_curtain)."""
    for case, fig_name, title in (
            ("terrain_net", "fig22_terrain_net.png",
             "terrain_net (7.6, fig. 22): rock rolls down the STL terrain and is stopped by the net"),
            ("terrain_curtain", "fig21_terrain_curtain.png",
             "terrain_curtain (7.6, fig. 21): curtain (free lower edge) on the slope, protection net at the foot")):
        results = run_all(case, [(case, [])], out, 1, end_time)
        run_dir, seconds, ok = results[case]
        try:
            n = _terrain_case_figure(case, run_dir, ok, os.path.join(out, fig_name), title)
        except (OSError, KeyError) as e:
            print("  %-16s no results (%s)" % (case, e))
            continue
        print("  %s: %.2f s simulated in %.1f s wall%s; rock centre x max %.3f m at %.3f s;"
              " %.2f iterations/step (max %d), %d unconverged"
              % (case, n["end"], seconds, "" if ok else " FAILED", n["x_max"], n["t_x_max"], n["iterations"],
                 n["it_max"], n["unconverged"]))
        for name in ("curtain", "protection net"):
            if name in n:
                print("    %s: largest displacement %.3f m at %.2f s" % (name, n[name][0], n[name][1]))


def _net_section(ax, fem, k, axis_fixed, value, colour, label):
    """Draws the net's line AXIS_FIXED = VALUE (x-z view) at rest and at output step K."""
    line = section_nodes(fem, axis_fixed, value)
    line = line[np.argsort(fem["x"][line, 0])]
    x0 = fem["x"][line]
    xd = x0 + fem["u"][k, line, :]
    ax.plot(x0[:, 0], x0[:, 2], color=colour, lw=1, ls=":")
    ax.plot(xd[:, 0], xd[:, 2], color=colour, lw=1.5, marker=".", ms=3,
            label="%s at t = %.3f s" % (label, fem["t"][k]))


def study_special(out, jobs, end_time):
    """7.7, figs. 24-25: a rigid cluster of spheres (rock_cluster) and a coarse net as a sieve (net_sieve)."""
    # ---- rock_cluster, fig. 24
    case = "rock_cluster"
    results = run_all(case, [(case, [])], out, 1, end_time)
    run_dir, seconds, ok = results[case]
    loaded = load_run(case, run_dir)
    if loaded:
        dem, fem, m, c = loaded
        cp = dem["cpos"][:, 0, :]
        centre = m.node(220)
        all_nodes = np.arange(fem["x"].shape[0])
        d = max_deflection(fem, all_nodes)
        kd = int(np.argmax(d))
        fig, axes = plt.subplots(1, 2, figsize=(13, 4.8))
        ax = axes[0]
        for p in range(dem["pos"].shape[1]):
            ax.plot(dem["pos"][:, p, 0], dem["pos"][:, p, 2], color="0.7", lw=0.6,
                    label="the 5 spheres' centres" if p == 0 else None)
        ax.plot(cp[:, 0], cp[:, 2], color="tab:brown", lw=1.5, label="cluster centre of mass")
        ax.plot(cp[0, 0], cp[0, 2], "o", color="tab:brown", ms=4)
        kz = int(np.argmin(cp[:, 2]))
        for p in range(dem["pos"].shape[1]):
            ax.add_patch(plt.Circle((dem["pos"][kz, p, 0], dem["pos"][kz, p, 2]), dem["radius"][p], fill=False,
                                    color="tab:brown", ls="--", lw=0.8))
        y_line = fem["x"][section_nodes(fem, 0, 0.0), 1]
        y_line = y_line[np.argmin(np.abs(y_line - cp[kz, 1]))]
        _net_section(ax, fem, kd, 1, y_line, "tab:blue", "net line y = %.2f m" % y_line)
        ax.set_aspect("equal")
        ax.set_xlim(-1.6, 1.6)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("z [m]")
        ax.set_title("(a) x-z paths; rock (dashed) at its lowest, t = %.3f s" % dem["t"][kz])
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
        ax = axes[1]
        for t0, t1 in nc_results.contact_intervals(c.start_time, c.end_time, c.in_contact.astype(float), 0.5):
            ax.axvspan(t0, t1, color="tab:orange", alpha=0.25, lw=0)
        ax.plot([], [], color="tab:orange", alpha=0.4, lw=6, label="rock in contact with the net")
        ax.plot(dem["t"], cp[:, 2], color="tab:brown", lw=1.2, label="cluster centre of mass z")
        ax.plot(m.time, centre, color="tab:blue", lw=1.2, label="net centre node 220 u_z")
        ax.plot(fem["t"], -d, color="tab:blue", lw=0.8, ls="--", label="- max |u| over all net nodes")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("[m]")
        ax.set_title("(b) rock height and net deflection")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
        fig.suptitle("rock_cluster (7.7, fig. 24): a rigid cluster of 5 spheres caught by a horizontal net")
        save(fig, os.path.join(out, "fig24_rock_cluster.png"))
        first = c.end_time[np.argmax(c.in_contact > 0)] if c.in_contact.any() else float("nan")
        k2 = kz + int(np.argmax(cp[kz:, 2]))
        print("  %s: %.2f s simulated in %.1f s wall%s; first contact %.3f s; centre of mass z: start %.3f,"
              " min %.3f at %.3f s, rebound max %.3f at %.3f s, end %.3f m; centre node min %.3f m at %.3f s,"
              " end %.3f m; max |u| %.3f m at %.3f s; |x|,|y| of the centre <= %.3f m; %.2f it/step (max %d),"
              " %d unconverged"
              % (case, dem["t"][-1], seconds, "" if ok else " FAILED", first, cp[0, 2], cp[kz, 2], dem["t"][kz],
                 cp[k2, 2], dem["t"][k2], cp[-1, 2], centre.min(), m.time[np.argmin(centre)], centre[-1],
                 d[kd], fem["t"][kd], np.abs(cp[:, :2]).max(), c.iterations.mean(), c.iterations.max(),
                 int((c.converged == 0).sum())))
    # ---- net_sieve, fig. 25
    case = "net_sieve"
    results = run_all(case, [(case, [])], out, 1, end_time)
    run_dir, seconds, ok = results[case]
    loaded = load_run(case, run_dir)
    if not loaded:
        return
    dem, fem, m, c = loaded
    names = {0: ("big sphere", "tab:red"), 1: ("small sphere", "tab:green")}
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.8))
    ax = axes[0]
    # the x-z view of each sphere's path, with the net line y = -0.25 m (a cable the big one strikes)
    d = max_deflection(fem, np.arange(fem["x"].shape[0]))
    kd = int(np.argmax(d))
    _net_section(ax, fem, kd, 1, -0.25, "tab:blue", "net cable y = -0.25 m")
    cables_x = np.unique(np.round(fem["x"][:, 0], 6))
    ax.plot(cables_x, np.zeros_like(cables_x), "|", color="tab:blue", ms=10, label="cables along y (x positions)")
    for p, (name, colour) in names.items():
        pos = dem["pos"][:, p, :]
        R = dem["radius"][p]
        ax.plot(pos[:, 0], pos[:, 2], color=colour, lw=1.5, label="%s (R %.2f m) centre" % (name, R))
        for k in (0, len(dem["t"]) - 1):
            ax.add_patch(plt.Circle((pos[k, 0], pos[k, 2]), R, fill=False, color=colour, lw=0.8,
                                    ls="-" if k == 0 else "--"))
        if p == 0:
            kz = int(np.argmin(pos[:, 2]))
            ax.add_patch(plt.Circle((pos[kz, 0], pos[kz, 2]), R, fill=False, color=colour, lw=0.8, ls=":"))
    ax.set_aspect("equal")
    ax.set_xlim(-1.1, 1.1)
    ax.set_ylim(-1.1, 0.8)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.set_title("(a) x-z paths (circles: start, lowest, end)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="lower left")
    ax = axes[1]
    for t0, t1 in nc_results.contact_intervals(c.start_time, c.end_time, c.in_contact.astype(float), 0.5):
        ax.axvspan(t0, t1, color="tab:orange", alpha=0.25, lw=0)
    ax.plot([], [], color="tab:orange", alpha=0.4, lw=6, label="big sphere in contact")
    for p, (name, colour) in names.items():
        ax.plot(dem["t"], dem["pos"][:, p, 2], color=colour, lw=1.2, label=name + " z")
        ax.plot(dem["t"], dem["vel"][:, p, 2] / 10, color=colour, lw=0.8, ls="--", label=name + " v_z / 10 [m/s]")
    ax.plot(m.time, m.node(30), color="tab:blue", lw=1.2, label="net node 30 u_z")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("[m]")
    ax.set_title("(b) heights, velocities and net deflection")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="lower left")
    fig.suptitle("net_sieve (7.7, fig. 25): the small sphere falls through the coarse net, the big one is thrown back")
    save(fig, os.path.join(out, "fig25_net_sieve.png"))
    big_z, big_v = dem["pos"][:, 0, 2], dem["vel"][:, 0, 2]
    small_v = dem["vel"][-1, 1, 2]
    free_fall = -5.0 - 9.81 * dem["t"][-1]
    first = c.end_time[np.argmax(c.in_contact > 0)] if c.in_contact.any() else float("nan")
    print("  %s: %.3f s simulated in %.1f s wall%s; small sphere end z %.3f m, v_z %.4f m/s (free fall %.4f);"
          " big sphere first contact %.4f s, min z %.3f m at %.3f s, end v_z %+.3f m/s (impact %.3f);"
          " node 30 min u_z %.3f m; %.2f it/step (max %d), %d unconverged"
          % (case, dem["t"][-1], seconds, "" if ok else " FAILED", dem["pos"][-1, 1, 2], small_v, free_fall, first,
             big_z.min(), dem["t"][np.argmin(big_z)], big_v[-1], big_v.min(), m.node(30).min(),
             c.iterations.mean(), c.iterations.max(), int((c.converged == 0).sum())))


# ---- the interface Jacobian against the plain exchange (docs/notes/interface_jacobian.md) --

# case: (end time [s] covering the main impact, monitor node, component of its peak (0 x, 2 z),
# the --set keys of the rock–net restitution, wall-time cap per run [s], 5x dt included, extra sets).
# Rock–net ζ is the mean of the rock's and the net wall's (dem_solver/README.md): where the net
# wall has its own restitution both are set (the terrain cases' rock–ground pair changes with it).
ROCK_NET = ["dem.materials.0.restitution", "dem.net_wall.restitution"]
# the terrain cases roll 1.9 s before the net: far steps (x10, 0.056 m of rolling per step, less
# than the near distance 0.3 m) for the approach, in every variant and in the reference
FAR = ["coupler.efficiency.far_step=true", "coupler.efficiency.far_step_factor=10"]
JACOBIAN_CASES = [
    ("rest_position", 1.5, 1, 2, ["dem.materials.0.restitution"], 60, True, []),
    ("cable_impact", 1.0, 1, 2, ["dem.materials.0.restitution"], 60, True, []),
    ("net_sieve", 0.2, 30, 2, ROCK_NET, 60, True, []),
    ("angled_net", 0.2, 220, 2, ROCK_NET, 60, True, []),
    ("steel_net", 0.15, 220, 2, ROCK_NET, 45, True, []),
    ("rock_cluster", 0.55, 220, 2, ROCK_NET, 40, True, []),
    ("terrain_net", 2.15, 52, 0, ROCK_NET, 40, True, FAR),
    ("terrain_curtain", 2.15, 52, 0, ROCK_NET, 40, True, FAR),
]
JACOBIAN_CORS = ["0.1", "0.3", "0.5", "1.0"]
# references at Δt/10 for every COR where they are cheap, at COR 0.3 elsewhere (the budget)
JACOBIAN_REF_ALL_CORS = ("rest_position", "cable_impact", "net_sieve")
JACOBIAN_REF_CAP_S = 90
JACOBIAN_VARIANTS = [
    ("aitken", "plain Aitken", ["coupler.interface_jacobian=false"]),
    ("iqn", "plain IQN-ILS", ["coupler.interface_jacobian=false", "coupler.relaxation.method=iqn-ils"]),
    ("jac_aitken", "Jacobian + Aitken", ["coupler.interface_jacobian=true", "coupler.relaxation.method=aitken",
                                         "coupler.relaxation.alpha=1.0", "coupler.relaxation.first_iteration_cap=1.0"]),
    ("jac_iqn", "Jacobian + IQN-ILS", ["coupler.interface_jacobian=true", "coupler.relaxation.method=iqn-ils",
                                       "coupler.relaxation.alpha=1.0"]),
]
TARGET_AVG, TARGET_MAX, TARGET_PEAK_PCT = 3.0, 10, 3.0


def jacobian_sets(case_dt, factor, end, cor, cor_keys, variant_sets, extra):
    dt = "%g" % (case_dt * factor)
    return (variant_sets + extra + ["coupler.dt=" + dt, "fem.analysis.dt_s=" + dt,
                                    "coupler.end_time=%g" % end, "fem.analysis.end_time_s=%g" % end]
            + ["%s=%s" % (k, cor) for k in cor_keys])


def cor_dt_variants(dt0, end, cor_keys, five, extra, variants, base_sets=()):
    """(label, --set list) of every variant at every COR and Δt (the case's, and 5x it when
    `five`), labelled <variant>_cor<COR>_dt<factor>x; base_sets go before each variant's own."""
    return [("%s_cor%s_dt%dx" % (name, cor, factor),
             jacobian_sets(dt0, factor, end, cor, cor_keys, list(base_sets) + vsets, extra))
            for cor in JACOBIAN_CORS for factor in ((1, 5) if five else (1,)) for name, _, vsets in variants]


def case_dt_of(case):
    with open(os.path.join(ROOT, "cases", case, "coupler.json")) as f:
        return float(json.load(f)["dt"])


def jacobian_metrics(run_dir, seconds, node, component):
    """The study's numbers of one run (partial for a stopped run: the coupler writes coupling.h5 as it stops)."""
    import h5py
    info = {}
    done = os.path.join(run_dir, "done.json")
    if os.path.exists(done):
        with open(done) as f:
            info = json.load(f)
    r = dict(seconds=seconds, rc=info.get("returncode"), timed_out=info.get("timed_out", False))
    try:
        with h5py.File(os.path.join(run_dir, "coupling.h5"), "r") as f:
            st = f["/steps"]
            it = np.array(st["iterations"])
            # /steps/iterations counts the accepted try; /iterations has a row for every
            # iteration of every try, numbered by the step it tried
            tried = np.array(f["/iterations/step"]).astype(int).ravel()
            tries = np.bincount(tried, minlength=len(it))[:len(it)]
            # a contact step: the accepted step ended in contact, or a try of it touched (a
            # try rejected at a contact's onset is followed by a shorter step that may end
            # before the rock arrives: its iterations belong to the contact all the same)
            touched = np.any(np.array(f["/iterations/contact_force"]).reshape(len(tried), -1) != 0,
                             axis=1)
            contact = np.array(st["in_contact"]) > 0
            contact[np.unique(tried[touched & (tried < len(it))])] = True
            r.update(steps=len(it), t_end=float(st["time"][-1]) if len(it) else 0.0,
                     unconverged=int((np.array(st["converged"]) == 0).sum()),
                     rejected=int(np.array(st["rejected"]).sum()),
                     contact_steps=int(contact.sum()),
                     it_avg=float(it[contact].mean()) if contact.any() else float("nan"),
                     it_max=int(it[contact].max()) if contact.any() else 0,
                     all_avg=float(tries[contact].mean()) if contact.any() else float("nan"),
                     all_max=int(tries[contact].max()) if contact.any() else 0,
                     finished=int(f.attrs.get("finished", 0)))
            e = f["/energy"]
            created, inp, above = np.array(e["created"]), np.array(e["input"]), np.array(e["above"])
            ok = np.isfinite(created) & (inp > 0)
            r["created_pct"] = float((created[ok] / inp[ok]).max() * 100) if ok.any() else float("nan")
            r["energy_fired"] = bool(above.any())
    except (OSError, KeyError, IndexError) as e:
        r["error"] = str(e)
        return r
    try:
        m = nc_results.load_monitor(run_dir)
        u = m.node(node, component)
        r["peak"] = float(np.abs(u).max())
        r["t_peak"] = float(m.time[int(np.argmax(np.abs(u)))])
    except (OSError, KeyError, ValueError):
        r["peak"] = float("nan")
    return r


def jacobian_status(r):
    """Short exit status: 0, 3, the code, 'cap' (stopped at the wall-time cap), '-' (no results)."""
    if "error" in r:
        return "-"
    if r.get("timed_out"):
        return "cap@%.3g" % r["t_end"]
    return str(r["rc"])


def run_reliable(r):
    """Exit 0, no step accepted unconverged, the energy guard silent."""
    return jacobian_status(r) == "0" and r["unconverged"] == 0 and not r["energy_fired"]


def meets_iterations(r):
    """The iteration target, counted over every try of a contact step (a rejected try's
    iterations are work the step cost)."""
    return r["all_avg"] <= TARGET_AVG and r["all_max"] <= TARGET_MAX


def tries_note(r):
    """' (all tries a/m)' where rejected tries added iterations to the contact steps."""
    if r["contact_steps"] == 0 or (r["all_max"] == r["it_max"] and abs(r["all_avg"] - r["it_avg"]) < 5e-3):
        return ""
    return " (all tries %.1f/%d)" % (r["all_avg"], r["all_max"])


def jacobian_meets(r, ref_peak):
    """(iterations target, reliability target (finished, 0 unconverged, no energy), peak target or None)."""
    if "error" in r:
        return False, False, None
    its = r["contact_steps"] > 0 and meets_iterations(r)
    reliable = (not r["timed_out"]) and r["rc"] in (0, 3) and r["finished"] == 1 and r["unconverged"] == 0 \
        and not r["energy_fired"]
    peak = None
    # only a run that reached its end time is compared (a stopped one may not have had its peak yet)
    if ref_peak is not None and r.get("finished") == 1 and np.isfinite(r.get("peak", float("nan"))):
        peak = abs(r["peak"] - ref_peak) / ref_peak * 100 <= TARGET_PEAK_PCT
    return its, reliable, peak


# The speed target: rest_position over 4 s, COR 0.5, strong 3e-2 s with the Jacobian against weak
# coupling at 1e-3 s, with and without it (run one at a time)
SPEED_ROWS = [(label, sets + ["dem.materials.0.restitution=0.5", "coupler.end_time=4", "fem.analysis.end_time_s=4"])
              for label, sets in [
                  ("speed_strong3e-2_jac", ["coupler.scheme=strong", "coupler.dt=3e-2", "fem.analysis.dt_s=3e-2"]
                   + JACOBIAN_VARIANTS[2][2]),
                  ("speed_weak1e-3_plain", ["coupler.scheme=weak", "coupler.dt=1e-3", "fem.analysis.dt_s=1e-3",
                                            "coupler.interface_jacobian=false"]),
                  ("speed_weak1e-3_jac", ["coupler.scheme=weak", "coupler.dt=1e-3", "fem.analysis.dt_s=1e-3",
                                          "coupler.interface_jacobian=true"])]]
SPEED_ROUNDS = 7


def speed_row(run_dir):
    """(coupler wall time, steps, mean iterations per step, exit status) of a speed run."""
    import h5py
    with h5py.File(os.path.join(run_dir, "coupling.h5"), "r") as f:
        wall = float(f["/timing/total"][0])
        it = np.array(f["/steps/iterations"])
    with open(os.path.join(run_dir, "done.json")) as f:
        rc = json.load(f).get("returncode")
    return wall, len(it), float(it.mean()), rc


def study_speed(out, jobs, end_time):
    """The Jacobian study's speed target alone: its three rest_position runs, %d rounds taking turns, medians."""
    del jobs, end_time   # one run at a time, over the whole 4 s: what is measured is wall time
    shutil.rmtree(out, ignore_errors=True)   # measured afresh every time
    runs = {label: [] for label, _ in SPEED_ROWS}
    for k in range(SPEED_ROUNDS):
        print("  round %d of %d" % (k + 1, SPEED_ROUNDS))
        for label, sets in SPEED_ROWS:
            _, run_dir, seconds, _ = run("rest_position", label, sets, os.path.join(out, "round%d" % k), None, 300)
            runs[label].append((seconds,) + speed_row(run_dir))
    lines = ["| rest_position, COR 0.5, 4 s | wall [s] | coupler wall [s] | steps | it/step | exit |",
             "|---|---|---|---|---|---|"]
    for label, r in runs.items():
        lines.append("| %s | %.2f | %.2f | %d | %.2f | %s |" % (
            label[6:], statistics.median(x[0] for x in r), statistics.median(x[1] for x in r), r[0][2], r[0][3],
            "/".join(sorted(set(str(x[4]) for x in r)))))
    strong, weak = runs["speed_strong3e-2_jac"], runs["speed_weak1e-3_jac"]
    for what, i in (("end to end", 0), ("coupler wall time", 1)):
        pairs = sorted(w[i] / s[i] for s, w in zip(strong, weak))
        lines.append("")
        lines.append("strong3e-2_jac against weak1e-3_jac, %s: %.1fx (median of the medians), each round's pair "
                     "%.1f-%.1fx" % (what, statistics.median(w[i] for w in weak) / statistics.median(s[i] for s in strong),
                                     pairs[0], pairs[-1]))
    table = "\n".join(lines)
    print(table)
    with open(os.path.join(out, "speed_table.md"), "w") as f:
        f.write(table + "\n")
    print("  wrote", os.path.join(out, "speed_table.md"))


study_speed.__doc__ = study_speed.__doc__ % SPEED_ROUNDS


def study_jacobian(out, jobs, end_time):
    """Interface Jacobian vs plain exchange, Aitken and IQN-ILS, 8 cases x COR x dt (targets of the coupling)."""
    # 1. the speed rows, one run at a time (`speed` measures them over several rounds)
    speed_results = run_all("rest_position", SPEED_ROWS, os.path.join(out, "rest_position"), 1, None, 300)
    # 2. the matrix, cheap cases first so that an interrupted study has them; then the references
    rows = {}
    refs = {}
    for case, end, node, comp, cor_keys, cap, five, extra in JACOBIAN_CASES:
        end = end_time or end
        dt0 = case_dt_of(case)
        variants = cor_dt_variants(dt0, end, cor_keys, five, extra, JACOBIAN_VARIANTS)
        case_out = os.path.join(out, case)
        print("  %s: %d runs to %g s, cap %d s" % (case, len(variants), end, cap))
        results = run_all(case, variants, case_out, jobs, None, cap)
        for label, (run_dir, seconds, ok) in results.items():
            rows[(case, label)] = jacobian_metrics(run_dir, seconds, node, comp)
    for case, end, node, comp, cor_keys, cap, five, extra in JACOBIAN_CASES:
        end = end_time or end
        dt0 = case_dt_of(case)
        cors = JACOBIAN_CORS if case in JACOBIAN_REF_ALL_CORS else ["0.3"]
        variants = [("ref_cor%s_dt0.1x" % cor, jacobian_sets(dt0, 0.1, end, cor, cor_keys, JACOBIAN_VARIANTS[2][2], extra))
                    for cor in cors]
        results = run_all(case, variants, os.path.join(out, case), jobs, None, JACOBIAN_REF_CAP_S)
        for label, (run_dir, seconds, ok) in results.items():
            r = jacobian_metrics(run_dir, seconds, node, comp)
            cor = label.split("_")[1][3:]
            # a reference stopped at the cap still counts once its peak is behind it (by 5 % of the run)
            if ("error" not in r and r["unconverged"] == 0 and not r["energy_fired"] and r["peak"] > 0
                    and (r.get("finished") == 1 or r["t_peak"] < r["t_end"] - 0.05 * end)):
                refs[(case, cor)] = r
            rows[(case, label)] = r
    jacobian_tables(out, rows, refs, speed_results)
    jacobian_figures(out, rows, refs)


def jacobian_cell(r, ref):
    if "error" in r:
        return "no results"
    cell = "%s %s/%d u%d r%d" % (jacobian_status(r), "%.1f" % r["it_avg"] if np.isfinite(r["it_avg"]) else "-",
                                  r["it_max"], r["unconverged"], r["rejected"])
    cell += tries_note(r)
    if r["energy_fired"]:
        cell += " E%+.0f%%" % r["created_pct"]
    if ref is not None and r.get("finished") == 1 and np.isfinite(r.get("peak", float("nan"))):
        cell += " %+.1f%%" % ((r["peak"] - ref["peak"]) / ref["peak"] * 100)
    return cell + " %.0fs" % r["seconds"]


def jacobian_tables(out, rows, refs, speed_results):
    print("\n  cell: exit status (0, 3 NOT reliable, 1 failed, cap@t: stopped at the wall-time cap at t)"
          " it/step avg/max in contact, u unconverged steps accepted, r rejected tries, E energy created"
          " (guard fired, % of input), peak vs the fine reference, wall time")
    lines = []
    head = "| case | end [s] | COR | Δt [s] | " + " | ".join(v[1] for v in JACOBIAN_VARIANTS) + " | reference peak (Δt/10) |"
    lines.append(head)
    lines.append("|" + "---|" * (5 + len(JACOBIAN_VARIANTS)))
    tally = {v[0]: dict(runs=0, its=0, reliable=0, peak=0, peak_n=0, all=0) for v in JACOBIAN_VARIANTS}
    for case, end, node, comp, cor_keys, cap, five, extra in JACOBIAN_CASES:
        dt0 = case_dt_of(case)
        for cor in JACOBIAN_CORS:
            ref = refs.get((case, cor))
            for factor in ((1, 5) if five else (1,)):
                cells = []
                for name, _, _ in JACOBIAN_VARIANTS:
                    r = rows.get((case, "%s_cor%s_dt%dx" % (name, cor, factor)))
                    if r is None:
                        cells.append("not run")
                        continue
                    use_ref = ref if factor == 1 else None
                    cells.append(jacobian_cell(r, use_ref))
                    its, reliable, peak = jacobian_meets(r, use_ref["peak"] if use_ref else None)
                    t = tally[name]
                    t["runs"] += 1
                    t["its"] += its
                    t["reliable"] += reliable
                    if peak is not None:
                        t["peak_n"] += 1
                        t["peak"] += peak
                    # at the case's Δt "all" includes the peak check, so a run without a reference is not counted
                    t["all"] += its and reliable and (peak is True or factor != 1)
                refcell = "-"
                if factor == 1:
                    rr = rows.get((case, "ref_cor%s_dt0.1x" % cor))
                    if ref is not None:
                        refcell = "%.4f m at %.3f s%s" % (ref["peak"], ref["t_peak"],
                                                          "" if ref.get("finished") == 1 else " (run to %.3g s)" % ref["t_end"])
                    elif rr is not None:
                        refcell = "none (%s, %d unconverged)" % (jacobian_status(rr), rr.get("unconverged", -1))
                lines.append("| %s | %g | %s | %g | %s | %s |" % (case, end, cor, dt0 * factor, " | ".join(cells), refcell))
    lines.append("")
    lines.append("| variant | runs | iterations ≤ %g avg / ≤ %d max in contact, every try counted | reliable (finished, 0 unconverged, no energy) "
                 "| peak within %g %% (of runs with a reference) | all targets |" % (TARGET_AVG, TARGET_MAX, TARGET_PEAK_PCT))
    lines.append("|---|---|---|---|---|---|")
    for name, title, _ in JACOBIAN_VARIANTS:
        t = tally[name]
        lines.append("| %s | %d | %d | %d | %d of %d | %d |" % (title, t["runs"], t["its"], t["reliable"], t["peak"],
                                                                t["peak_n"], t["all"]))
    lines.append("")
    lines.append("| rest_position, COR 0.5, 4 s | wall [s] | coupler wall [s] | steps | it/step | exit |")
    lines.append("|---|---|---|---|---|---|")
    for label in ("speed_strong3e-2_jac", "speed_weak1e-3_plain", "speed_weak1e-3_jac"):
        run_dir, seconds, ok = speed_results[label]
        try:
            wall, steps, it_mean, rc = speed_row(run_dir)
            lines.append("| %s | %.1f | %.2f | %d | %.2f | %s |" % (label[6:], seconds, wall, steps, it_mean, rc))
        except (OSError, KeyError) as e:
            lines.append("| %s | no results (%s) | | | | |" % (label[6:], e))
    table = "\n".join(lines)
    print(table)
    with open(os.path.join(out, "jacobian_table.md"), "w") as f:
        f.write(table + "\n")
    print("  wrote", os.path.join(out, "jacobian_table.md"))


def targets_map(path, variants, rows, refs, title, width=None, decimals=2):
    """One panel per variant, a cell per case x (COR, Δt) coloured by the targets it meets,
    with the average (to `decimals`) / max iterations per contact step written in. refs: the
    fine-step references of the peak at the case's Δt, or None where the peak is not a
    target of the map. width: of the figure in inches (default 3 per panel, at least 10)."""
    cols = [(cor, f) for f in (1, 5) for cor in JACOBIAN_CORS]
    width = width or max(3.0 * len(variants), 10.0)
    fig, axes = plt.subplots(1, len(variants), figsize=(width, 5.4), sharey=True)
    colours = {"all": "#4caf50", "noref": "#c5e1a5", "reliable": "#ffd54f", "its": "#90caf9",
               "none": "#ef9a9a", "missing": "#eeeeee"}
    for ax, (name, label, _) in zip(np.atleast_1d(axes), variants):
        for i, case in enumerate(c[0] for c in JACOBIAN_CASES):
            for j, (cor, factor) in enumerate(cols):
                r = rows.get((case, "%s_cor%s_dt%dx" % (name, cor, factor)))
                if r is None or "error" in r:
                    colour, text = colours["missing"], "not run" if r is None else "-"
                else:
                    if refs is None:
                        its, reliable, peak = meets_iterations(r), run_reliable(r), True
                    else:
                        ref = refs.get((case, cor)) if factor == 1 else None
                        its, reliable, peak = jacobian_meets(r, ref["peak"] if ref else None)
                    kind = ("all" if its and reliable and (peak is True or factor != 1) else
                            "noref" if its and reliable and peak is None else
                            "reliable" if reliable else "its" if its else "none")
                    colour = colours[kind]
                    text = "%s\n%d" % ("%.*f" % (decimals, r["all_avg"]) if np.isfinite(r["all_avg"]) else "-",
                                        r["all_max"])
                    if r["timed_out"]:
                        text += "\ncap"
                    elif r["rc"] not in (0, 3):
                        text += "\nexit %s" % r["rc"]
                    elif r["unconverged"]:
                        text += "\nu%d" % r["unconverged"]
                ax.add_patch(plt.Rectangle((j, i), 1, 1, facecolor=colour, edgecolor="white"))
                ax.text(j + 0.5, i + 0.5, text, ha="center", va="center", fontsize=6)
        ax.set_xlim(0, len(cols))
        ax.set_ylim(len(JACOBIAN_CASES), 0)
        ax.set_xticks(np.arange(len(cols)) + 0.5)
        ax.set_xticklabels(["%s\n%s" % (cor, "Δt" if f == 1 else "5Δt") for cor, f in cols], fontsize=7)
        ax.set_yticks(np.arange(len(JACOBIAN_CASES)) + 0.5)
        ax.set_yticklabels([c[0] for c in JACOBIAN_CASES], fontsize=8)
        ax.set_title(textwrap.fill(label, 34), fontsize=9)
        ax.set_xlabel("rock–net COR, coupling step")
    if refs is None:
        kinds = ("all", "reliable", "its", "none", "missing")
        names = ["iterations met, reliable", "reliable, iterations above target",
                 "iterations met, not reliable", "neither", "not run"]
    else:
        kinds = ("all", "noref", "reliable", "its", "none", "missing")
        names = ["all targets met", "iterations and reliability met, no reference for the peak",
                 "reliable, iterations above target", "iterations met, not reliable", "neither",
                 "not run (5Δt dropped: time budget)"]
    handles = [plt.Rectangle((0, 0), 1, 1, facecolor=colours[k]) for k in kinds]
    fig.legend(handles, names, loc="lower center", ncol=len(kinds), fontsize=8)
    fig.suptitle(textwrap.fill(title, int(12 * width)), fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 0.95))
    fig.savefig(path, dpi=120)
    plt.close(fig)
    print("  wrote", path)


def jacobian_figures(out, rows, refs):
    """The targets map of the Jacobian study, and the iterations over time of three cases."""
    targets_map(os.path.join(out, "jacobian_targets.png"), JACOBIAN_VARIANTS, rows, refs,
                "interface iterations per contact step, every try counted (average / max; u: unconverged "
                "steps accepted, cap: stopped at the wall-time cap) and the targets (≤ 3 / ≤ 10, reliable, "
                "peak within 3 %)", width=18.0, decimals=1)
    # iterations over time at the case's Δt, COR 0.3, for the two light cases and one net case
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    for ax, case in zip(axes, ("rest_position", "cable_impact", "net_sieve")):
        for name, title, _ in JACOBIAN_VARIANTS:
            try:
                c = nc_results.load_coupling(os.path.join(out, case, "%s_cor0.3_dt1x" % name))
            except (OSError, KeyError):
                continue
            ax.step(c.end_time, c.iterations, where="pre", lw=0.9, label=title)
        ax.set_title("%s, COR 0.3, the case's Δt" % case, fontsize=9)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("interface iterations per step")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    save(fig, os.path.join(out, "jacobian_iterations.png"))


# ---- the work test: eq. (35) against work_tolerance 1e-6 (docs/notes/interface_jacobian.md) --

WORK_TOLERANCE = "1e-6"
WORK_VARIANTS = [("paper", "eq. (35)", ["coupler.work_tolerance=0"]),
                 ("work", "work_tolerance " + WORK_TOLERANCE, ["coupler.work_tolerance=" + WORK_TOLERANCE])]


def interface_mismatch_pct(run_dir):
    """The run's summed interface work mismatch (coupling.h5 /energy/interface_created) as a
    share of its input energy (%): positive = created at the interface, negative = lost."""
    import h5py
    with h5py.File(os.path.join(run_dir, "coupling.h5"), "r") as f:
        inp = np.array(f["/energy/input"])
        return float(np.array(f["/energy/interface_created"]).sum() / inp.max() * 100) if inp.max() > 0 else float("nan")


def compare_variants(out, jobs, end_time, variants, table_name):
    """Jacobian + Aitken as in the Jacobian study, each of `variants` (name, label, --set list)
    on top, 8 cases x COR x dt; a table of the iteration counts, the interface mismatch and
    each variant's peak against the first's, written to out/table_name, and the targets map
    to out/NAME_targets.png (table_name NAME_table.md or NAME.md)."""
    rows = {}
    for case, end, node, comp, cor_keys, cap, five, extra in JACOBIAN_CASES:
        end = end_time or end
        dt0 = case_dt_of(case)
        runs = cor_dt_variants(dt0, end, cor_keys, five, extra, variants, JACOBIAN_VARIANTS[2][2])
        print("  %s: %d runs to %g s, cap %d s" % (case, len(runs), end, cap))
        for label, (run_dir, seconds, ok) in run_all(case, runs, os.path.join(out, case), jobs, None, cap).items():
            r = jacobian_metrics(run_dir, seconds, node, comp)
            if "error" not in r:
                r["mismatch_pct"] = interface_mismatch_pct(run_dir)
            rows[(case, label)] = r
    first = variants[0]
    lines = ["| case | COR | Δt | " + " | ".join(v[1] for v in variants) + " | " +
             " | ".join("peak: %s against %s" % (v[1], first[1]) for v in variants[1:]) + " |",
             "|---|---|---|" + "---|" * (2 * len(variants) - 1)]
    meets, reliable = ({v[0]: 0 for v in variants} for _ in range(2))
    averages = {v[0]: [] for v in variants}
    all_averages = {v[0]: [] for v in variants}
    for case, end, node, comp, cor_keys, cap, five, extra in JACOBIAN_CASES:
        for cor in JACOBIAN_CORS:
            for factor in ((1, 5) if five else (1,)):
                cells, runs = [], {}
                for name, _, _ in variants:
                    r = runs[name] = rows.get((case, "%s_cor%s_dt%dx" % (name, cor, factor)), {"error": "missing"})
                    if "error" in r:
                        cells.append("no results")
                        continue
                    ok = meets_iterations(r)
                    meets[name] += ok
                    reliable[name] += run_reliable(r)
                    averages[name].append(r["it_avg"])
                    all_averages[name].append(r["all_avg"])
                    cell = "%s %.2f/%d r%d%s mismatch %+.2f %%" % (jacobian_status(r), r["it_avg"], r["it_max"],
                                                                   r["rejected"], tries_note(r), r["mismatch_pct"])
                    cells.append("**%s**" % cell if ok else cell)
                p = runs[first[0]]
                for name, _, _ in variants[1:]:
                    w = runs[name]
                    cells.append("%+.2f %%" % ((w["peak"] - p["peak"]) / p["peak"] * 100)
                                 if "error" not in p and "error" not in w and p.get("peak", 0) > 0 else "-")
                lines.append("| %s | %s | %s | %s |" % (case, cor, "case" if factor == 1 else "5×", " | ".join(cells)))
    lines.append("")
    lines.append("Cell: exit status · iterations per contact step, average/largest, of the accepted tries · "
                 "r rejected tries, and the average/largest with their iterations counted too · "
                 "the summed interface work mismatch, %% of the input energy (negative: lost); "
                 "**bold**: ≤ %g and ≤ %d counting every try."
                 % (TARGET_AVG, TARGET_MAX))
    lines.append("")
    for name, label, _ in variants:
        n = len(averages[name])
        lines.append("- %s: %d of %d runs reliable; %d of %d within ≤ %g on average and ≤ %d at most; "
                     "%.2f iterations per contact step (%.2f counting every try), the mean of the runs' averages"
                     % (label, reliable[name], n, meets[name], n, TARGET_AVG, TARGET_MAX,
                        float(np.mean(averages[name])) if n else float("nan"),
                        float(np.mean(all_averages[name])) if n else float("nan")))
    text = "\n".join(lines) + "\n"
    print(text)
    with open(os.path.join(out, table_name), "w") as f:
        f.write(text)
    print("  wrote", os.path.join(out, table_name))
    stem = os.path.splitext(table_name)[0]
    stem = stem[:-len("_table")] if stem.endswith("_table") else stem
    targets_map(os.path.join(out, stem + "_targets.png"), variants, rows, None,
                "interface iterations per contact step, every try counted (average / max; u: unconverged "
                "steps accepted, cap: stopped at the wall-time cap) against the targets ≤ %g / ≤ %d, "
                "and reliability" % (TARGET_AVG, TARGET_MAX))


def study_work(out, jobs, end_time):
    """Jacobian + Aitken with eq. (35) against the work test (work_tolerance), 8 cases x COR x dt."""
    compare_variants(out, jobs, end_time, WORK_VARIANTS, "work_table.md")


ESTIMATE_VARIANTS = [("paper", "eq. (35)", ["coupler.work_tolerance=0", "coupler.newton_estimate=0"]),
                     ("estimate", "newton_estimate 0.1",
                      ["coupler.work_tolerance=0", "coupler.newton_estimate=0.1"]),
                     ("work_estimate", "work_tolerance %s and newton_estimate 0.1" % WORK_TOLERANCE,
                      ["coupler.work_tolerance=" + WORK_TOLERANCE, "coupler.newton_estimate=0.1"])]


def study_estimate(out, jobs, end_time):
    """Jacobian + Aitken with eq. (35), with the Newton error estimate (newton_estimate), and
    with both it and the work test; 8 cases x COR x dt."""
    compare_variants(out, jobs, end_time, ESTIMATE_VARIANTS, "estimate_table.md")


_NO_WORK = ["coupler.work_tolerance=0"]
_COMPLIANCE = _NO_WORK + ["coupler.interface_compliance=true"]
COMPLIANCE_VARIANTS = [("paper", "eq. (35)", _NO_WORK + ["coupler.newton_estimate=0"]),
                       ("compliance", "interface_compliance",
                        _COMPLIANCE + ["coupler.newton_estimate=0", "coupler.structure_predictor=false",
                                       "coupler.compliance_proximity=false"]),
                       ("compliance_estimate", "interface_compliance and newton_estimate 0.1",
                        _COMPLIANCE + ["coupler.newton_estimate=0.1", "coupler.structure_predictor=false",
                                       "coupler.compliance_proximity=false"]),
                       ("compliance_predictor_estimate",
                        "interface_compliance, structure_predictor and newton_estimate 0.1",
                        _COMPLIANCE + ["coupler.newton_estimate=0.1", "coupler.structure_predictor=true",
                                       "coupler.compliance_proximity=false"]),
                       ("compliance_proximity",
                        "interface_compliance, structure_predictor and compliance_proximity",
                        _COMPLIANCE + ["coupler.newton_estimate=0", "coupler.structure_predictor=true",
                                       "coupler.compliance_proximity=true"]),
                       ("compliance_proximity_estimate",
                        "interface_compliance, structure_predictor, compliance_proximity and newton_estimate 0.1",
                        _COMPLIANCE + ["coupler.newton_estimate=0.1", "coupler.structure_predictor=true",
                                       "coupler.compliance_proximity=true"])]


def study_compliance(out, jobs, end_time):
    """Jacobian + Aitken with eq. (35), with the structure's compliance in the DEM
    (interface_compliance), with and without the Newton error estimate, the structure
    predictor and the compliance at the nodes a rock in contact may reach
    (compliance_proximity); 8 cases x COR x dt."""
    compare_variants(out, jobs, end_time, COMPLIANCE_VARIANTS, "compliance_table.md")


NEWTON_VARIANTS = [("secant", "eq. (34) throughout", ["coupler.relaxation.newton_contraction=0"]),
                   ("theta0.2", "newton_contraction 0.2", ["coupler.relaxation.newton_contraction=0.2"]),
                   ("theta0.5", "newton_contraction 0.5", ["coupler.relaxation.newton_contraction=0.5"]),
                   ("newton", "plain Newton", ["coupler.relaxation.method=none"])]


def study_newton(out, jobs, end_time):
    """Jacobian + Aitken: eq. (34) throughout, newton_contraction 0.2 and 0.5, plain Newton; 8 cases x COR x dt."""
    compare_variants(out, jobs, end_time, NEWTON_VARIANTS, "newton_table.md")


TOLERANCE_VARIANTS = [("tol1e-6", "tolerance 1e-6", ["coupler.tolerance=1e-6"]),
                      ("tol1e-5", "tolerance 1e-5", ["coupler.tolerance=1e-5"]),
                      ("tol1e-4", "tolerance 1e-4", ["coupler.tolerance=1e-4"])]


def study_tolerance(out, jobs, end_time):
    """Jacobian + Aitken with eq. (35) at the interface tolerance 1e-6, 1e-5 and 1e-4; 8 cases x COR x dt."""
    compare_variants(out, jobs, end_time, TOLERANCE_VARIANTS, "tolerance_table.md")


STUDIES = {
    "timestep": study_timestep,
    "relaxation": study_relaxation,
    "relaxation_dt": study_relaxation_dt,
    "restitution": study_restitution,
    "cable_impact": study_cable_impact,
    "angled_net": study_angled_net,
    "terrain": study_terrain,
    "special": study_special,
    "jacobian": study_jacobian,
    "speed": study_speed,
    "work": study_work,
    "estimate": study_estimate,
    "compliance": study_compliance,
    "newton": study_newton,
    "tolerance": study_tolerance,
}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("study", nargs="?", choices=sorted(STUDIES))
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "studies"))
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--end-time", type=float, help="shorten every run to this end time [s]")
    parser.add_argument("--list", action="store_true", help="list the studies")
    args = parser.parse_args()
    if args.list or not args.study:
        for name, fn in sorted(STUDIES.items()):
            print("%-14s %s" % (name, fn.__doc__.strip().splitlines()[0]))
        return
    out = os.path.join(args.out, args.study)
    print("study %s -> %s" % (args.study, out))
    STUDIES[args.study](out, args.jobs, args.end_time)


if __name__ == "__main__":
    main()
