#!/usr/bin/python3
"""A run report: one Markdown page with PNG plots of a coupled run (or of a standalone FEM or
DEM folder) in an engineer's terms, and a short summary on stdout.

    scripts/report.py RUN_DIR [--out FILE.md] [--particle N] [--smooth N]
                      [--speed-threshold V] [--dem-json FILE]

Writes RUN_DIR/report.md (or FILE.md) and its plots into RUN_DIR/report/ (FILE/ beside
FILE.md). Reads fem.h5, dem.h5, coupling.h5, dem.json and coupler.log of the folder; whatever is
missing is named in the report and skipped. The rock is the body (sphere or cluster) with the
largest kinetic energy at the start (the heaviest when all are at rest), or the one holding
particle N (index into /particles). Each criterion (impact, braking, verdict) is defined in the
report itself. Exit status: 0 report written; 2 bad arguments or a folder that is not a run
(none of fem.h5, dem.h5, coupling.h5), or a file that cannot be read.

stdout lines (one "key: value" each, numbers in SI units): report, rock, impact, braking,
deceleration, rope force every step (fem.h5 /element_sets), breaking load (one line per element
set that has one), rope force (output steps), rope strain, deflection, reaction, energy,
reliability, contact, iterations, verdict. Ropes above their breaking load are named at the top
of the report, after the verdict (the model has no rope failure). The rope strain leaves out
the element sets whose strain is no rope's (fem.json types sliding_cable: per segment, as the
rope slides through its shackles; brake: the stroke; post) and names them in report.md.
"""
import argparse
import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import nc_results  # noqa: E402

G0 = 9.81  # m/s^2: the unit "g" of decelerations


class NotARun(Exception):
    pass


def fmt(x, unit="", digits=4):
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "n/a"
    s = "%.*g" % (digits, x)
    return s + (" " + unit if unit else "")


def fmt_energy(x):
    return fmt(x / 1e3, "kJ") if x is not None and np.isfinite(x) and abs(x) >= 1e4 else fmt(x, "J")


# ---------------------------------------------------------------- loading

def load_run(run, dem_json):
    """dict of what the folder holds; notes lists what is missing and why."""
    if not os.path.isdir(run):
        raise NotARun("%s: not a folder" % run)
    files = {name: os.path.join(run, name) for name in ("fem.h5", "dem.h5", "coupling.h5")}
    if not any(os.path.exists(p) for p in files.values()):
        raise NotARun("%s: not a run folder (none of fem.h5, dem.h5, coupling.h5 is there)" % run)
    r = dict(notes=[], fem=None, dem=None, coupling=None, energy=None, dem_cfg=None)
    loaders = (("fem", "fem.h5", nc_results.load_fem), ("dem", "dem.h5", nc_results.load_dem),
               ("coupling", "coupling.h5", nc_results.load_coupling))
    for key, name, loader in loaders:
        if not os.path.exists(files[name]):
            r["notes"].append("%s is missing: no %s results" % (name, {"fem": "net", "dem": "rock",
                                                                     "coupling": "coupling"}[key]))
            continue
        try:
            r[key] = loader(run)
        except (OSError, KeyError, ValueError) as e:
            raise NotARun("%s: cannot be read: %s" % (files[name], e))
    if r["coupling"] is not None:
        try:
            r["energy"] = nc_results.load_energy(run)
        except (OSError, KeyError) as e:
            r["notes"].append("coupling.h5 has no energy balance (%s)" % e)
    cfg = dem_json or os.path.join(run, "dem.json")
    if os.path.exists(cfg):
        try:
            r["dem_cfg"] = nc_results.load_json(cfg)
        except (OSError, ValueError) as e:
            r["notes"].append(str(e))
    elif r["dem"] is not None:
        r["notes"].append("%s is missing: rock masses and energies unknown (--dem-json FILE)" % cfg)
    r["verdict_line"] = nc_results.run_verdict_line(run)
    r["set_types"] = None   # element type of each fem.json element set, when readable
    try:
        with open(os.path.join(run, "fem.json")) as fh:
            r["set_types"] = [str(es.get("type", "cable")) for es in json.load(fh).get("element_sets", [])]
    except (OSError, ValueError, AttributeError, TypeError):
        pass
    return r


def densities(cfg):
    if cfg is None:
        return None
    try:
        return [float(m["density_kg_m3"]) for m in cfg["materials"]]
    except (KeyError, TypeError, ValueError):
        return None


def gravity(cfg):
    g = np.array((cfg or {}).get("gravity", [0.0, 0.0, -9.81]), dtype=float)
    return g


# ---------------------------------------------------------------- analysis

def state_at(t, x, v, tq, side):
    """Position and velocity at time tq from the output series, extrapolated from the nearest
    output on `side` ("before": the last output at or before tq; "after": the first at or after)
    with the constant acceleration of that output and its neighbour on the same side (exact in
    free flight; no sample from the other side of tq is used)."""
    if side == "before":
        k = int(np.searchsorted(t, tq, side="right")) - 1
        k = max(k, 0)
        nb = k - 1
    else:
        k = int(np.searchsorted(t, tq, side="left"))
        k = min(k, len(t) - 1)
        nb = k + 1
    a = np.zeros(3)
    if 0 <= nb < len(t) and t[nb] != t[k]:
        a = (v[k] - v[nb]) / (t[k] - t[nb])
    tau = tq - t[k]
    return x[k] + v[k] * tau + 0.5 * a * tau ** 2, v[k] + a * tau


def hermite(t0, x0, v0, t1, x1, v1, tq):
    """Cubic Hermite interpolation of the position between two outputs (uses both velocities)."""
    h = t1 - t0
    if h <= 0:
        return x0
    s = (tq - t0) / h
    h00 = 2 * s ** 3 - 3 * s ** 2 + 1
    h10 = s ** 3 - 2 * s ** 2 + s
    h01 = -2 * s ** 3 + 3 * s ** 2
    h11 = s ** 3 - s ** 2
    return h00 * x0 + h10 * h * v0 + h01 * x1 + h11 * h * v1


def contact_windows(r):
    """(windows [(t0, t1)], source text, per-step (time, force magnitude) or None)."""
    c = r["coupling"]
    if c is not None and len(c.time):
        f = c.force_magnitude()
        return (nc_results.contact_intervals(c.start_time, c.end_time, f, threshold=0.0),
                "coupling steps with a non-zero total contact force (coupling.h5 /steps/contact_force)",
                (c.end_time, f))
    d = r["dem"]
    if d is not None and d.walls_force is not None and len(d.time) > 1:
        f = np.linalg.norm(d.walls_force, axis=2).sum(axis=1)
        start = np.concatenate([[d.time[0]], d.time[:-1]])
        return (nc_results.contact_intervals(start, d.time, f, threshold=0.0),
                "DEM output steps with a non-zero wall force (dem.h5 /walls/force; no coupling.h5)",
                (d.time, f))
    return [], "not available (neither coupling.h5 nor DEM wall forces)", None


def impact_time(r, t, x, v, first):
    """The time of first contact: the start of the first coupling step with a contact force,
    moved into that step by the gap at its start (coupling.h5 /steps/min_gap of the step
    before: the smallest particle-to-cable surface distance) closed at the rock's velocity
    along its direction of motion under constant acceleration."""
    c = r["coupling"]
    what = "the start of the first contact window"
    if c is None or c.min_gap is None or not len(c.time) or r.get("n_bodies", 1) > 1:
        return first, what
    k = int(np.argmax(c.force_magnitude() > 0))
    if k == 0 or not (0.0 < c.min_gap[k - 1] < 1e29):
        return first, what
    gap, dt = float(c.min_gap[k - 1]), float(c.dt[k])
    _, v0 = state_at(t, x, v, first, "before")
    _, v1 = state_at(t, x, v, first + dt, "before")
    s0 = float(np.linalg.norm(v0))
    if s0 <= 0:
        return first, what
    dhat = v0 / s0
    acc = float((v1 - v0) @ dhat) / dt
    # gap = s0 tau + acc tau^2 / 2, smallest root in [0, dt]
    if abs(acc) > 1e-12:
        disc = s0 * s0 + 2.0 * acc * gap
        tau = (-s0 + np.sqrt(disc)) / acc if disc >= 0 else dt
    else:
        tau = gap / s0
    tau = min(max(tau, 0.0), dt)
    return first + tau, ("the start of the first contact step (%s s) plus the time to close the gap "
                         "of %s at its start (coupling.h5 /steps/min_gap)" % (fmt(first, digits=6), fmt(gap, "m")))


def rock_net_windows(r, rk):
    """Contact windows of one rock of a run with several: the DEM output steps at which one of
    its spheres is within its radius (+ net_wall.cable_radius_m) of a segment of the DEM's net
    (dem.h5 /net/position, /net/edges); None when the DEM has no net."""
    d = r["dem"]
    if d.net_position is None or d.net_edges is None or not len(d.net_edges):
        return None
    cable = float(((r["dem_cfg"] or {}).get("net_wall") or {}).get("cable_radius_m", 0.0))
    j0 = d.net_first_step or 0
    touch = np.zeros(len(d.time), bool)
    for k in range(j0, min(len(d.time), j0 + len(d.net_position))):
        a = d.net_position[k - j0][d.net_edges[:, 0]]
        b = d.net_position[k - j0][d.net_edges[:, 1]]
        ab = b - a
        L2 = np.maximum(np.sum(ab * ab, axis=1), 1e-300)
        for i in rk.particles:
            c = d.position[k, i]
            s = np.clip(np.sum((c - a) * ab, axis=1) / L2, 0.0, 1.0)
            dist = np.linalg.norm(a + s[:, None] * ab - c, axis=1)
            if dist.min() <= d.radius[i] + cable:
                touch[k] = True
                break
    start = np.concatenate([[d.time[0]], d.time[:-1]])
    return nc_results.contact_intervals(start, d.time, touch.astype(float), threshold=0.5)


def pick_rock(rocks, particle):
    if particle is not None:
        for rk in rocks:
            if particle in rk.particles:
                return rk
        raise NotARun("--particle %d: dem.h5 has particles 0 … %d" %
                      (particle, sum(len(x.particles) for x in rocks) - 1))
    ke0 = np.array([rk.kinetic[0] for rk in rocks])
    if np.all(np.isfinite(ke0)) and ke0.max() > 0:
        return rocks[int(np.argmax(ke0))]
    size = np.array([rk.mass if np.isfinite(rk.mass) else len(rk.particles) for rk in rocks])
    return rocks[int(np.argmax(size))]


def analyse_rock(r, args, windows):
    d = r["dem"]
    rocks = nc_results.rocks(d, densities(r["dem_cfg"]))
    rk = pick_rock(rocks, args.particle)
    t, x, v = d.time, rk.position, rk.velocity
    r["n_bodies"] = len(rocks)
    wsource = None
    if len(rocks) > 1:
        own = rock_net_windows(r, rk)
        if own is not None and own:
            # the outputs may miss the first touch: take the start of a coupling contact window
            # that begins within two output intervals before this rock's first one
            dto = float(t[1] - t[0]) if len(t) > 1 else 0.0
            near_starts = [a for a, _ in windows if own[0][0] - 2 * dto <= a <= own[0][0] + dto]
            if near_starts:
                own[0] = (min(near_starts[0], own[0][0]), own[0][1])
        if own is not None:
            windows = own
            wsource = ("DEM output steps at which one of this rock's spheres touches a segment of the "
                       "DEM's net (dem.h5 /net; the run has %d bodies; the first window starts at the "
                       "coupling step with contact force that begins up to two output intervals before "
                       "it, if there is one)" % len(rocks))
    speed = np.linalg.norm(v, axis=1)
    out = dict(rock=rk, n_bodies=len(rocks), t=t, x=x, v=v, speed=speed, windows=windows, wsource=wsource,
               bound=float(np.max(np.linalg.norm(d.position[0, rk.particles] - x[0], axis=1)
                                  + d.radius[rk.particles])))
    first = windows[0][0] if windows else None
    if first is not None and first <= t[-1]:
        tc, refined = impact_time(r, t, x, v, first)
        xc, vc = state_at(t, x, v, tc, "before")
        out["impact_source"] = ("state at t = %s s, %s; extrapolated from the last DEM output "
                                "before it (%s s) with the acceleration of the two outputs before "
                                "(exact in free flight)"
                                % (fmt(tc, digits=6), refined,
                                   fmt(t[max(0, np.searchsorted(t, tc, "right") - 1)])))
    else:
        k = int(np.argmax(speed))
        xc, vc, tc = x[k], v[k], t[k]
        out["impact_source"] = "no contact: the largest speed of the run, at t = %s s" % fmt(tc)
    out.update(tc=tc, xc=xc, vc=vc, vimp=float(np.linalg.norm(vc)), contact=first is not None)
    out["eimp"] = 0.5 * rk.mass * out["vimp"] ** 2
    dhat = vc / out["vimp"] if out["vimp"] > 0 else np.array([0.0, 0.0, -1.0])
    out["dhat"] = dhat
    vd = v @ dhat
    out["vd"] = vd
    # deceleration along the impact direction: second-order central differences of v.d
    # (np.gradient, one-sided at the ends), then an optional centred moving average
    if len(t) > 2:
        a = np.gradient(vd, t)
        if args.smooth > 1:
            a = np.convolve(a, np.ones(args.smooth) / args.smooth, mode="same")
        out["decel_g"] = -a / G0
    else:
        out["decel_g"] = np.full(len(t), np.nan)
    out["vthr"] = max(args.speed_threshold, 0.05 * out["vimp"])
    if not out["contact"]:
        return out
    # braking: from first contact until v.d first reaches zero (linear in v.d between outputs;
    # the position there by cubic Hermite interpolation with the velocities)
    after = np.where(t > tc)[0]
    tp, xp, vp, vdp = tc, xc, vc, out["vimp"]
    stop = None
    for k in after:
        if vd[k] <= 0.0:
            s = vdp / (vdp - vd[k]) if vdp != vd[k] else 0.0
            ts = tp + s * (t[k] - tp)
            stop = (ts, hermite(tp, xp, vp, t[k], x[k], v[k], ts))
            break
        tp, xp, vp, vdp = t[k], x[k], v[k], vd[k]
    out["stopped_in_run"] = stop is not None
    ts, xs = stop if stop is not None else (t[-1], x[-1])
    out["t_stop"], out["x_stop"] = ts, xs
    out["brake_dist"] = float(np.linalg.norm(xs - xc))
    out["brake_along"] = float((xs - xc) @ dhat)
    out["brake_time"] = ts - tc
    win = np.zeros(len(t), bool)
    for a0, a1 in windows:
        win |= (t >= a0) & (t <= a1 + (t[1] - t[0] if len(t) > 1 else 0))
    dg = np.where(win, out["decel_g"], np.nan)
    out["decel_peak"] = (float(np.nanmax(dg)), float(t[int(np.nanargmax(dg))])) if np.any(np.isfinite(dg)) else None
    back = -vd[after]
    out["rebound"] = float(back.max()) if len(after) else 0.0
    out["rebound_time"] = float(t[after[int(np.argmax(back))]]) if len(after) else np.nan
    last_end = windows[-1][1]
    if last_end < t[-1]:
        _, vl = state_at(t, x, v, last_end, "after")
        out["leave_speed"] = float(-(vl @ dhat))
    else:
        out["leave_speed"] = None
    return out


def analyse_net(r):
    f = r["fem"]
    out = {}
    if not len(f.time):
        return out
    af = f.axial_force
    k, e = np.unravel_index(int(np.argmax(af)), af.shape)
    out["force_series"] = af.max(axis=1)
    out["force_peak"] = (float(af[k, e]), int(e), float(f.time[k]))
    # rope strain: not of the sets whose strain is no rope's (a sliding rope's is per segment,
    # as the rope slides through its shackles; a brake's is its stroke; a post's)
    st = f.strain.copy()
    out["strain_skipped"] = []
    types = r.get("set_types")
    if types and f.element_set is not None and len(f.element_set) == st.shape[1]:
        for j, kind in enumerate(types):
            if kind in ("sliding_cable", "brake", "post") and (f.element_set == j).any():
                st[:, f.element_set == j] = -np.inf
                out["strain_skipped"].append("%d (%s)" % (j, kind))
        if not np.isfinite(st).any():
            st = f.strain.copy()
            out["strain_skipped"] = []
    ks, es = np.unravel_index(int(np.argmax(st)), st.shape)
    out["strain_series"] = st.max(axis=1)
    out["strain_peak"] = (float(st[ks, es]), int(es), float(f.time[ks]))
    if f.reference_length is not None:
        el = np.where(np.isfinite(st), st, 0.0) * f.reference_length[None, :]
        ke, ee = np.unravel_index(int(np.argmax(el)), el.shape)
        out["elong_series"] = el.max(axis=1)
        out["elong_peak"] = (float(el[ke, ee]), int(ee), float(f.time[ke]))
    if f.coordinates is not None and f.elements is not None:
        out["mid"] = lambda el_: 0.5 * (f.coordinates[f.elements[el_, 0]] + f.coordinates[f.elements[el_, 1]])
    out["defl_series"] = np.linalg.norm(f.displacement, axis=2).max(axis=1)
    if f.reaction.size:
        res = np.linalg.norm(f.reaction.sum(axis=1), axis=1)
        single = np.linalg.norm(f.reaction, axis=2)
        kr = int(np.argmax(res))
        k1, s1 = np.unravel_index(int(np.argmax(single)), single.shape)
        out["reaction"] = dict(res=res, single=single.max(axis=1), res_peak=(float(res[kr]), float(f.time[kr])),
                               single_peak=(float(single[k1, s1]), int(f.support_nodes[s1]), float(f.time[k1])))
    return out


def verdict(rock, r, windows):
    """(word, sentence) — the criteria are written out in the report."""
    if rock is None:
        return "n/a", "no verdict: dem.h5 is missing (no rock)"
    if r["fem"] is None or r["fem"].position is None or not len(r["fem"].time):
        return "n/a", "no verdict: fem.h5 is missing (no net)"
    d, vthr = rock["dhat"], rock["vthr"]
    if not rock["contact"]:
        net, xe = r["fem"].position[-1], rock["x"][-1]
        g = gravity(r["dem_cfg"])
        ghat = g / np.linalg.norm(g) if np.linalg.norm(g) > 0 else np.array([0.0, 0.0, -1.0])
        if xe @ ghat - rock["bound"] > (net @ ghat).max():
            return "passed through", ("passed through without touching the net: at the end below its lowest "
                                      "node, moving at %s" % fmt(float(rock["speed"][-1]), "m/s"))
        return "no contact", "no contact: the rock never touched the net (largest speed %s)" % fmt(rock["vimp"], "m/s")
    xe, ve = rock["x"][-1], rock["v"][-1]
    net = r["fem"].position[-1]
    g = gravity(r["dem_cfg"])
    ghat = g / np.linalg.norm(g) if np.linalg.norm(g) > 0 else np.array([0.0, 0.0, -1.0])
    R = rock["bound"]
    beyond = xe @ d - R > (net @ d).max()
    below = xe @ ghat - R > (net @ ghat).max()
    se = float(np.linalg.norm(ve))
    if beyond or (below and se > vthr):
        where = "beyond the net's deformed surface" if beyond else "below the net's lowest node"
        return "passed through", ("passed through: at the end (t = %s s) the rock is %s, moving at %s"
                                  % (fmt(rock["t"][-1]), where, fmt(se, "m/s")))
    windows = rock["windows"]
    touching = bool(windows) and windows[-1][1] >= rock["t"][-1] - 1e-12
    if rock["n_bodies"] == 1 and r["coupling"] is not None and len(r["coupling"].time):
        touching = r["coupling"].force_magnitude()[-1] > 0
    ls = rock.get("leave_speed")
    if not touching and ls is not None and ls > vthr:
        e = ls / rock["vimp"]
        return "rebounded", ("rebounded: the rock left the net at %s against the impact direction "
                             "(impact %s, apparent restitution %.3g)" % (fmt(ls, "m/s"), fmt(rock["vimp"], "m/s"), e))
    back = -float(rock["vd"][-1])
    if touching and back > vthr:
        return "rebounded", ("rebounded: at the end the rock is still touching the net but moving back at %s "
                             "against the impact direction (impact %s, apparent restitution at least %.3g)"
                             % (fmt(back, "m/s"), fmt(rock["vimp"], "m/s"), back / rock["vimp"]))
    # extent of the net across the impact direction, widened by the rock's size
    e1 = np.cross(d, [1.0, 0.0, 0.0])
    if np.linalg.norm(e1) < 0.1:
        e1 = np.cross(d, [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(d, e1)
    inside = all((net @ e).min() - R <= xe @ e <= (net @ e).max() + R for e in (e1, e2))
    reached = np.nanmin(rock["vd"][rock["t"] > rock["tc"]]) <= vthr if np.any(rock["t"] > rock["tc"]) else False
    if reached and inside:
        return "stopped", ("stopped: braked from %s to 0 in %s s over %s; at the end %s, %s the net"
                           % (fmt(rock["vimp"], "m/s"), fmt(rock["brake_time"]), fmt(rock["brake_dist"], "m"),
                              fmt(se, "m/s"), "in contact with" if touching else "within the extent of"))
    if not inside:
        return "undecided", ("undecided: the rock ends outside the net's extent (t = %s s, %s) without "
                             "passing through it" % (fmt(rock["t"][-1]), fmt(se, "m/s")))
    return "undecided", ("undecided: still braking at the end of the run (%s along the impact direction)"
                         % fmt(float(rock["vd"][-1]), "m/s"))


# ---------------------------------------------------------------- plots

def shade(ax, windows):
    for i, (a, b) in enumerate(windows):
        ax.axvspan(a, b, color="tab:orange", alpha=0.15, lw=0, label="contact" if i == 0 else None)


def save(fig, path, written):
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    written.append(path)


def plot_rock(rock, windows, cforce, pngdir, written):
    t = rock["t"]
    fig, ax = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    ax[0].plot(t, rock["speed"], label="speed |v|")
    ax[0].plot(t, rock["vd"], "--", label="v along the impact direction")
    ax[0].set_ylabel("velocity [m/s]")
    ke = rock["rock"].kinetic
    big = np.any(np.isfinite(ke)) and np.nanmax(np.abs(ke)) >= 1e4
    scale, unit = (1e3, "kJ") if big else (1.0, "J")
    ax[1].plot(t, ke / scale, label="kinetic energy (translation + rotation)")
    ax[1].set_ylabel("kinetic energy [%s]" % unit)
    ax[2].plot(t, rock["decel_g"], label="deceleration along the impact direction (gravity included)")
    if cforce is not None and np.isfinite(rock["rock"].mass) and rock["n_bodies"] == 1:
        ax[2].plot(cforce[0], cforce[1] / (rock["rock"].mass * G0), lw=0.8,
                   label="net contact force / rock weight (coupling steps)")
    ax[2].set_ylabel("deceleration [g]")
    ax[2].set_xlabel("time [s]")
    for a in ax:
        shade(a, windows)
        a.grid(True, alpha=0.3)
        a.legend(fontsize=8)
    p = os.path.join(pngdir, "rock.png")
    save(fig, p, written)
    return p


def plot_net(r, net, windows, pngdir, written):
    f = r["fem"]
    fig, ax = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    ax[0].plot(f.time, net["force_series"] / 1e3)
    ax[0].set_ylabel("largest rope force [kN]")
    if "elong_series" in net:
        ax[1].plot(f.time, net["elong_series"] * 1e3, label="largest element elongation (mm)")
    ax[1].plot(f.time, net["strain_series"] * 1e3, "--", label="largest strain (per mille)")
    ax[1].set_ylabel("elongation [mm], strain [‰]")
    ax[1].legend(fontsize=8)
    ax[2].plot(f.time, net["defl_series"])
    ax[2].set_ylabel("largest deflection |u| [m]")
    ax[2].set_xlabel("time [s]")
    for a in ax:
        shade(a, windows)
        a.grid(True, alpha=0.3)
    p = os.path.join(pngdir, "net.png")
    save(fig, p, written)
    return p


def plot_reactions(r, net, windows, pngdir, written):
    f, re = r["fem"], net["reaction"]
    fig, ax = plt.subplots(figsize=(7, 3.6))
    ax.plot(f.time, re["res"] / 1e3, label="resultant |Σ R|")
    ax.plot(f.time, re["single"] / 1e3, "--", label="largest single support |R|")
    shade(ax, windows)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("support reaction [kN]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    p = os.path.join(pngdir, "reactions.png")
    save(fig, p, written)
    return p


def plot_energy(en, windows, pngdir, written):
    fig, ax = plt.subplots(figsize=(7, 4.5))
    t = en.time
    scale, unit = (1e3, "kJ") if np.nanmax(np.abs(en.input)) >= 1e4 else (1.0, "J")
    for name, style in (("input", "k-"), ("fem_kinetic", "-"), ("fem_elastic", "-"), ("fem_potential", ":"),
                        ("dem_kinetic", "-"), ("dem_elastic", "-"), ("dem_potential", ":")):
        y = getattr(en, name)
        if y is not None:
            ax.plot(t, y / scale, style, lw=1, label=name.replace("_", " "))
    for name in ("fem_dissipated", "dem_dissipated", "external_work"):
        y = getattr(en, name)
        if y is not None:
            ax.plot(t, np.cumsum(y) / scale, "--", lw=1, label=name.replace("_", " ") + " (accumulated)")
    if en.created is not None:
        ax.plot(t, en.created / scale, "r-", lw=1.5, label="created")
    shade(ax, windows)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("energy [%s]" % unit)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    p = os.path.join(pngdir, "energy.png")
    save(fig, p, written)
    return p


def plot_iterations(c, windows, pngdir, written):
    fig, ax = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
    ax[0].plot(c.end_time, c.force_magnitude() / 1e3)
    ax[0].set_ylabel("contact force [kN]")
    ax[1].step(c.end_time, c.iterations, where="post")
    bad = c.converged == 0
    if bad.any():
        ax[1].plot(c.end_time[bad], c.iterations[bad], "rx", label="not converged")
        ax[1].legend(fontsize=8)
    ax[1].set_ylabel("interface iterations")
    ax[1].set_xlabel("time [s]")
    for a in ax:
        shade(a, windows)
        a.grid(True, alpha=0.3)
    p = os.path.join(pngdir, "iterations.png")
    save(fig, p, written)
    return p


# ---------------------------------------------------------------- report

def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", metavar="RUN_DIR")
    ap.add_argument("--out", help="Markdown file (default RUN_DIR/report.md); plots go to its stem folder")
    ap.add_argument("--particle", type=int, help="report the body holding this particle (index into /particles)")
    ap.add_argument("--smooth", type=int, default=1,
                    help="centred moving average of the deceleration over N output steps (default 1: none)")
    ap.add_argument("--speed-threshold", type=float, default=0.1,
                    help="smallest speed (m/s) that counts as moving; the threshold used is the larger "
                         "of this and 5%% of the impact speed (default 0.1)")
    ap.add_argument("--dem-json", help="dem.json for the masses (default RUN_DIR/dem.json)")
    args = ap.parse_args()
    if args.smooth < 1:
        ap.error("--smooth must be >= 1")
    try:
        return report(args)
    except NotARun as e:
        print("report: %s" % e, file=sys.stderr)
        return 2


def report(args):
    run = args.run
    r = load_run(run, args.dem_json)
    md_path = args.out or os.path.join(run, "report.md")
    pngdir = os.path.splitext(md_path)[0]
    os.makedirs(pngdir, exist_ok=True)
    rel = os.path.basename(pngdir)
    written = []
    summary = [("report", md_path)]
    md = ["# Run report: %s" % os.path.basename(os.path.abspath(run)), ""]
    windows, wsource, cforce = contact_windows(r)

    rock = None
    if r["dem"] is not None and r["dem"].position is not None and len(r["dem"].time):
        rock = analyse_rock(r, args, windows)
    net = analyse_net(r) if r["fem"] is not None else {}
    if rock is not None and rock["wsource"]:
        windows, wsource = rock["windows"], rock["wsource"]
    word, sentence = verdict(rock, r, windows)
    md += ["**Verdict: %s**" % sentence, ""]
    if r["fem"] is not None and r["fem"].overload:
        # forces beyond a rope's breaking load are a right answer for a rope that does not
        # break, which a real one would: said first, as run_case.sh does
        md += ["**Ropes above their breaking load** (the model has no rope failure):", ""]
        md += ["- " + line.replace("warning: ", "", 1) for line in r["fem"].overload.splitlines()]
        md += [""]
    if r["notes"]:
        md += ["Missing: " + "; ".join(r["notes"]) + ".", ""]

    # ---- rock
    md += ["## The rock", ""]
    if rock is None:
        md += ["Not available: no DEM results (dem.h5).", ""]
    else:
        rk = rock["rock"]
        summary.append(("rock", "body %d (particles %s), mass %s, %d bodies in the run"
                        % (rk.body, ",".join(str(i) for i in rk.particles), fmt(rk.mass, "kg", digits=6), rock["n_bodies"])))
        how = ("--particle %d" % args.particle if args.particle is not None else
               "the body with the largest kinetic energy at the start (the heaviest if all are at rest)")
        md += ["Body %d (%s), chosen as %s, of %d bodies. Mass %s (4/3 π r³ ρ per sphere, ρ from "
               "dem.json), size %s (largest distance of a sphere surface from the centre of mass)."
               % (rk.body, "sphere %d" % rk.particles[0] if len(rk.particles) == 1 else
                  "cluster of %d spheres" % len(rk.particles), how, rock["n_bodies"],
                  fmt(rk.mass, "kg"), fmt(rock["bound"], "m")), ""]
        md += ["| quantity | value |", "|---|---|",
               "| impact time | %s |" % fmt(rock["tc"], "s"),
               "| impact speed | %s |" % fmt(rock["vimp"], "m/s"),
               "| impact velocity | (%s) m/s |" % ", ".join("%.4g" % c for c in rock["vc"]),
               "| impact energy ½ m v² | %s |" % fmt_energy(rock["eimp"]),
               "| impact position (centre) | (%s) m |" % ", ".join("%.4g" % c for c in rock["xc"])]
        summary.append(("impact", "t %s s, speed %s m/s, energy %s J%s"
                        % (fmt(rock["tc"], digits=6), fmt(rock["vimp"], digits=6), fmt(rock["eimp"], digits=6),
                           "" if rock["contact"] else " (no contact: largest speed)")))
        if rock["contact"]:
            md += ["| braking distance | %s (along the impact direction %s) |" % (fmt(rock["brake_dist"], "m"),
                                                                                   fmt(rock["brake_along"], "m")),
                   "| braking time | %s%s |" % (fmt(rock["brake_time"], "s"),
                                                "" if rock["stopped_in_run"] else " (did not reach zero: to the end of the run)")]
            if rock["decel_peak"]:
                md += ["| peak deceleration | %s at %s |" % (fmt(rock["decel_peak"][0], "g"), fmt(rock["decel_peak"][1], "s"))]
            md += ["| largest speed back (against the impact direction) after contact | %s at %s |"
                   % (fmt(rock["rebound"], "m/s"), fmt(rock["rebound_time"], "s"))]
            summary.append(("braking", "distance %s m, along %s m, time %s s%s"
                            % (fmt(rock["brake_dist"], digits=6), fmt(rock["brake_along"], digits=6),
                               fmt(rock["brake_time"], digits=6), "" if rock["stopped_in_run"] else " (not stopped)")))
            if rock["decel_peak"]:
                summary.append(("deceleration", "peak %s g at %s s" % (fmt(rock["decel_peak"][0], digits=5),
                                                                      fmt(rock["decel_peak"][1], digits=5))))
        md += ["",
               "- *Impact*: %s. The impact direction is that of the impact velocity." % rock["impact_source"],
               "- *Braking distance*: displacement of the rock's centre from the impact to the moment its "
               "velocity along the impact direction first reaches zero (linear in that velocity between "
               "DEM outputs, the position there by cubic Hermite interpolation), or to the end of the "
               "run if it never does; *braking time*: the time between the two.",
               "- *Deceleration*: −d(v·d)/dt in g = %.2f m/s², d the impact direction (gravity included: "
               "−1 g in free fall along a downward impact), from the DEM's "
               "velocity outputs by second-order central differences (numpy.gradient, one-sided at the "
               "ends), %s; its peak is taken in the contact windows. The plot also shows the net's "
               "contact force over the rock's weight per coupling step (a finer measure, single rock only)."
               % (G0, "smoothed by a centred moving average over %d output steps" % args.smooth
                  if args.smooth > 1 else "not smoothed (--smooth N)"), ""]
        md += ["![rock](%s)" % os.path.join(rel, os.path.basename(plot_rock(rock, windows, cforce, pngdir, written))), ""]

    # ---- net
    md += ["## The net", ""]
    if r["fem"] is None:
        md += ["Not available: no FEM results (fem.h5).", ""]
    elif not net:
        md += ["fem.h5 has no output steps.", ""]
    else:
        f = r["fem"]

        def where(el):
            return " at (%s) m" % ", ".join("%.3g" % c for c in net["mid"](el)) if "mid" in net else ""
        fp, fe, ft = net["force_peak"]
        sp, se, stt = net["strain_peak"]
        md += ["| quantity | value |", "|---|---|",
               "| largest rope force (output steps) | %s in element %d (midpoint%s) at %s |" % (fmt(fp / 1e3, "kN"), fe, where(fe), fmt(ft, "s")),
               "| largest strain | %s in element %d at %s%s |" % (
                   fmt(sp, digits=4), se, fmt(stt, "s"),
                   "; not counted: element sets %s, whose strain is no rope's (a sliding rope's "
                   "is per segment, a brake's its stroke)" % ", ".join(net["strain_skipped"])
                   if net.get("strain_skipped") else "")]
        if "elong_peak" in net:
            ep, ee, et = net["elong_peak"]
            md += ["| largest element elongation (strain × L0) | %s in element %d at %s |" % (fmt(ep * 1e3, "mm"), ee, fmt(et, "s"))]
        node_xyz = ""
        if f.coordinates is not None and 0 <= f.max_node < len(f.coordinates):
            node_xyz = " (at (%s) m)" % ", ".join("%.3g" % c for c in f.coordinates[f.max_node])
        md += ["| peak deflection \\|u\\| (every step) | %s at node %d%s, %s |" % (fmt(f.max_u, "m"), f.max_node, node_xyz, fmt(f.max_time, "s"))]
        if f.set_peak_force is not None and len(f.set_peak_force):
            # every step's peak (fem.h5 /element_sets), which output steps can miss
            k = int(np.argmax(f.set_peak_force))
            pe = int(f.set_peak_element[k])
            md += ["| largest rope force (every step) | %s in element %d (midpoint%s) at %s |"
                   % (fmt(float(f.set_peak_force[k]) / 1e3, "kN"), pe, where(pe), fmt(float(f.set_peak_time[k]), "s"))]
            summary.append(("rope force every step", "peak %s N, element %d, t %s s, element set %d"
                            % (fmt(float(f.set_peak_force[k]), digits=6), pe, fmt(float(f.set_peak_time[k]), digits=6), k)))
            for j in range(len(f.set_peak_force)):
                b = float(f.set_breaking_load[j]) if f.set_breaking_load is not None else 0.0
                if b <= 0:
                    continue
                n = int(f.set_exceeded[j]) if f.set_exceeded is not None else 0
                md += ["| element set %d: breaking load %s | %s |" % (
                    j, fmt(b / 1e3, "kN"),
                    "exceeded in %d elements, first at %s; largest %s (%.3g×) — the model has no rope failure"
                    % (n, fmt(float(f.set_first_exceedance[j]), "s"), fmt(float(f.set_peak_force[j]) / 1e3, "kN"),
                       float(f.set_peak_force[j]) / b) if n > 0 else
                    "not reached: largest %s (%.3g×)" % (fmt(float(f.set_peak_force[j]) / 1e3, "kN"),
                                                        float(f.set_peak_force[j]) / b))]
                summary.append(("breaking load", "set %d: %s N, %d elements above it, largest %.4g times it"
                                % (j, fmt(b, digits=6), n, float(f.set_peak_force[j]) / b)))
        summary.append(("rope force", "peak %s N, element %d, t %s s" % (fmt(fp, digits=6), fe, fmt(ft, digits=6))))
        summary.append(("rope strain", "peak %s, element %d, t %s s" % (fmt(sp, digits=6), se, fmt(stt, digits=6))))
        summary.append(("deflection", "peak %s m, node %d, t %s s" % (fmt(f.max_u, digits=6), f.max_node, fmt(f.max_time, digits=6))))
        if "reaction" in net:
            rr = net["reaction"]
            md += ["| peak resultant support reaction \\|Σ R\\| | %s at %s |" % (fmt(rr["res_peak"][0] / 1e3, "kN"), fmt(rr["res_peak"][1], "s")),
                   "| peak single support reaction | %s at node %d, %s |" % (fmt(rr["single_peak"][0] / 1e3, "kN"),
                                                                              rr["single_peak"][1], fmt(rr["single_peak"][2], "s"))]
            summary.append(("reaction", "resultant peak %s N at t %s s, single peak %s N at node %d, t %s s"
                            % (fmt(rr["res_peak"][0], digits=6), fmt(rr["res_peak"][1], digits=6),
                               fmt(rr["single_peak"][0], digits=6), rr["single_peak"][1], fmt(rr["single_peak"][2], digits=6))))
        spacing = float(np.median(np.diff(f.time))) if len(f.time) > 1 else np.nan
        md += ["", "Rope values are the largest over all elements at each FEM output step (%d steps, %s … %s s, "
               "every %s: peaks between output steps are not seen; fem.json `output.interval_steps` sets the "
               "spacing); the peak deflection and the rope force \"every step\" are fem.h5's maxima over every "
               "step (/output/displacement attributes, /element_sets). Reactions: the force each "
               "support (fem.h5 /mesh/support_nodes, %d nodes) exerts on the net."
               % (len(f.time), fmt(f.time[0]), fmt(f.time[-1]), fmt(spacing, "s"), len(f.support_nodes)), ""]
        md += ["![net](%s)" % os.path.join(rel, os.path.basename(plot_net(r, net, windows, pngdir, written))), ""]
        if "reaction" in net:
            md += ["![reactions](%s)" % os.path.join(rel, os.path.basename(plot_reactions(r, net, windows, pngdir, written))), ""]

    # ---- energy
    md += ["## Energy balance and reliability", ""]
    en = r["energy"]
    if en is None or en.input is None or not len(en.time) or not np.any(np.isfinite(en.input)):
        md += ["Not available%s." % ("" if r["coupling"] is not None else ": no coupling.h5"), ""]
    else:
        diss_f = float(np.nansum(en.fem_dissipated)) if en.fem_dissipated is not None else np.nan
        diss_d = float(np.nansum(en.dem_dissipated)) if en.dem_dissipated is not None else np.nan
        ext = float(np.nansum(en.external_work)) if en.external_work is not None else np.nan
        md += ["| quantity | value |", "|---|---|",
               "| input energy (largest kinetic + elastic of both sides) | %s |" % fmt(float(en.input[-1]), "J"),
               "| created, largest / at the end | %s / %s |" % (fmt(float(np.nanmax(en.created)), "J"), fmt(float(en.created[-1]), "J")),
               "| dissipated by the net / the rocks | %s / %s |" % (fmt(diss_f, "J"), fmt(diss_d, "J")),
               "| external work | %s |" % fmt(ext, "J")]
        if en.closure is not None:
            md += ["| closure of the reports | %s |" % fmt(float(en.closure[-1]), "J")]
        md += ["", "Created = energy of both sides now − at the start − external work; a passive model keeps it "
               "≤ 0 (coupler/README.md, \"Energy balance\").", ""]
        summary.append(("energy", "input %s J, created max %s J end %s J, dissipated fem %s J dem %s J"
                        % (fmt(float(en.input[-1]), digits=6), fmt(float(np.nanmax(en.created)), digits=6),
                           fmt(float(en.created[-1]), digits=6), fmt(diss_f, digits=6), fmt(diss_d, digits=6))))
        md += ["![energy](%s)" % os.path.join(rel, os.path.basename(plot_energy(en, windows, pngdir, written))), ""]
    rel_line = r["verdict_line"]
    if rel_line is None and r["coupling"] is not None and en is not None and "reliable" in en.attrs:
        rel_line = "results are %s (coupling.h5 attribute reliable; coupler.log has no verdict line)" % (
            "reliable" if en.attrs["reliable"] == 1 else "NOT reliable")
    if rel_line is None:
        rel_line = "not known: no coupler.log verdict line%s" % (
            " and coupling.h5 has no reliable attribute (the coupler did not finish)" if r["coupling"] is not None else "")
    md += ["Coupler: %s" % rel_line, ""]
    summary.append(("reliability", rel_line))

    # ---- contact and iterations
    md += ["## Contact windows and interface iterations", ""]
    md += ["Contact windows: %s." % wsource, ""]
    if windows:
        md += ["| # | from [s] | to [s] | length [s] |", "|---|---|---|---|"]
        md += ["| %d | %.6g | %.6g | %.4g |" % (i + 1, a, b, b - a) for i, (a, b) in enumerate(windows[:30])]
        if len(windows) > 30:
            md += ["| … | %d more | | |" % (len(windows) - 30)]
        md += [""]
    else:
        md += ["No contact.", ""]
    summary.append(("contact", "%d windows%s" % (len(windows), ", first %s … %s s" % (fmt(windows[0][0], digits=6), fmt(windows[0][1], digits=6)) if windows else "")))
    c = r["coupling"]
    if c is not None and len(c.time):
        inc = c.force_magnitude() > 0
        kmax = int(np.argmax(c.iterations))
        md += ["| quantity | value |", "|---|---|",
               "| coupling steps | %d (%s, Δt %s … %s s) |" % (len(c.time), (en.attrs.get("scheme", "?") if en else "?"),
                                                              fmt(float(c.dt.min())), fmt(float(c.dt.max()))),
               "| iterations per step, mean / max | %.3g / %d (step %d, t = %s s) |" % (c.iterations.mean(), c.iterations[kmax], kmax, fmt(float(c.end_time[kmax]))),
               "| mean in contact / out of contact | %s / %s |" % (fmt(float(c.iterations[inc].mean())) if inc.any() else "n/a",
                                                                    fmt(float(c.iterations[~inc].mean())) if (~inc).any() else "n/a"),
               "| steps accepted unconverged | %d |" % int((c.converged == 0).sum()), ""]
        summary.append(("iterations", "mean %.4g, max %d, mean in contact %s, unconverged %d"
                        % (c.iterations.mean(), c.iterations[kmax], fmt(float(c.iterations[inc].mean())) if inc.any() else "n/a",
                           int((c.converged == 0).sum()))))
        md += ["![iterations](%s)" % os.path.join(rel, os.path.basename(plot_iterations(c, windows, pngdir, written))), ""]
    else:
        md += ["Interface iterations: not available (no coupling.h5).", ""]

    # ---- verdict criteria
    md += ["## Verdict criteria", "",
           "Checked in this order at the last DEM output; v_min = %s (the larger of %s m/s and 5 %% of the impact speed)."
           % (fmt(rock["vthr"], "m/s") if rock else "n/a", fmt(args.speed_threshold)), "",
           "- **passed through**: the whole rock (centre ± its size) is beyond the net's furthest deformed node "
           "along the impact direction, or below its lowest node (along gravity) moving faster than v_min "
           "(the latter also without any contact: a rock through an opening of the net);",
           "- **rebounded**: the rock is out of contact at the end and left its last contact window moving "
           "against the impact direction faster than v_min (rebound speed from the first DEM output after "
           "that window, extrapolated back to its end), or it still touches the net at the end but moves "
           "back faster than v_min; apparent restitution = rebound speed / impact speed;",
           "- **stopped**: its velocity along the impact direction came down to v_min or below after the "
           "impact and it ends within the net's extent across the impact direction (widened by the rock's size);",
           "- **undecided** otherwise (still braking at the end, or outside the net's extent); **no contact** "
           "when the rock never touched the net.", ""]
    with open(md_path, "w") as fh:
        fh.write("\n".join(md))
    summary.append(("verdict", sentence))
    for k, v in summary:
        print("%s: %s" % (k, v))
    return 0


if __name__ == "__main__":
    sys.exit(main())
