#!/usr/bin/python3
"""barrier_report — the quantities a rockfall-barrier test reports, from a coupled run folder.

Reads a run folder of scripts/run_case.sh on a barrier of scripts/make_barrier.py (fem.json,
fem.h5, dem.h5, coupling.h5) and prints, and with --plot draws:
  - maximum elongation: the largest displacement of the net along the impact direction (any
    net node, fem.h5 output steps only) and of `net_centre` (a monitor node: every FEM step),
    from the model's geometry; and net_centre's from where it was at the first contact (a net
    that sagged under its own weight before the block arrived);
  - impact: the block's velocity at its first contact with the net (coupling.h5, every step),
    from the dem.h5 output steps before it; its direction is the impact direction below;
  - braking time: from the first contact (coupling.h5, every step) to the block's stop, the
    first time its velocity along the impact direction is <= 0 (dem.h5 output steps, linear
    interpolation between them);
  - residual height: the lowest top-rope node at the end (z above the post bases) relative to
    the nominal height of the post tops (fem.h5, last output step);
  - peak axial forces per element set (ropes, brakes) and the largest anchor reaction (fem.h5
    output steps only: peaks between them are missed);
  - overload: per element set with a breaking load, the largest axial force of every FEM step
    against it and the elements that exceeded it (fem.h5 `/element_sets`, when present; the
    model has no rope failure, so forces beyond the breaking load are not physical);
  - force-time curves (--plot): the largest axial force of each element set and the largest
    anchor reaction at every fem.h5 output step;
  - the energy balance (coupling.h5 `/energy`, every accepted step): the block's kinetic
    energy at the first contact and at the end, and where it went: brakes (fem.h5
    `element_dissipated_energy`, output steps), the rest of the FEM's dissipation (Rayleigh and
    the integrator's), strain and kinetic energy of the structure, contact dissipation (DEM),
    the interface mismatch and the guard's created energy, the DEM's dissipation before the
    first net contact apart (a rock on a slope), the block's potential energy from the contact
    to the end; with coupling.h5's
    `fem_numerical_dissipated` also the split of the FEM's own dissipation into Rayleigh
    damping and the integrator's, and what no mechanism of the model accounts for (the
    integrator's share and the interface mismatch) against the block's energy.
--json FILE writes the same figures as JSON (keys as printed). Exit status 0, or 2 with a
message naming the file when the folder lacks what is needed or the block never touched the
net.
"""
import argparse
import json
import os
import sys

import numpy as np

try:
    import h5py
except ImportError:  # pragma: no cover
    sys.exit("barrier_report: needs h5py (Debian: python3-h5py)")


def fail(msg):
    print("barrier_report: " + msg, file=sys.stderr)
    sys.exit(2)


def read(path, name):
    if not os.path.exists(path):
        fail("%s: missing (is this a run folder of scripts/run_case.sh?)" % path)
    try:
        return h5py.File(path, "r")
    except OSError as e:
        fail("%s: cannot be read as HDF5 (%s)" % (path, e))


def dataset(f, path, key):
    if key not in f:
        fail("%s: no dataset %s" % (path, key))
    return f[key][()]


def block_velocity(dem, dem_path):
    """Centre-of-mass velocity of body 0 per dem.h5 output step: the mean of its spheres'
    velocities (the make_ead_block spheres are symmetric about the centre of mass)."""
    body = dataset(dem, dem_path, "particles/body")
    vel = dataset(dem, dem_path, "particles/velocity")
    sel = body == body.min()
    return dataset(dem, dem_path, "time"), vel[:, sel, :].mean(axis=1)


def first_crossing(t, y):
    """First time y <= 0 (linear interpolation), or None."""
    k = np.nonzero(y <= 0.0)[0]
    if len(k) == 0:
        return None
    k = k[0]
    if k == 0:
        return float(t[0])
    return float(t[k - 1] + (t[k] - t[k - 1]) * y[k - 1] / (y[k - 1] - y[k]))


def report(run):
    fem_json = os.path.join(run, "fem.json")
    if not os.path.exists(fem_json):
        fail("%s: missing" % fem_json)
    with open(fem_json) as fh:
        model = json.load(fh)
    for key in ("node_sets", "element_sets", "nodes"):
        if key not in model:
            fail("%s: no '%s' (not a make_barrier.py model?)" % (fem_json, key))
    sets = model["node_sets"]
    for key in ("net", "net_centre", "anchors", "post_tops", "post_bases"):
        if key not in sets:
            fail("%s: node_sets.%s missing (not a make_barrier.py model?)" % (fem_json, key))
    names = [s["name"] for s in model["element_sets"]]
    types = [s["type"] for s in model["element_sets"]]

    fem_path, dem_path, cpl_path = (os.path.join(run, n) for n in ("fem.h5", "dem.h5", "coupling.h5"))
    fem, dem, cpl = read(fem_path, "fem"), read(dem_path, "dem"), read(cpl_path, "coupling")

    # coupling steps
    ct = dataset(cpl, cpl_path, "steps/time")
    inc = dataset(cpl, cpl_path, "steps/in_contact")
    conv = dataset(cpl, cpl_path, "steps/converged")
    hit = np.nonzero(inc)[0]
    if not len(hit):
        fail("%s: the block never touched the barrier (/steps/in_contact is 0 in all %d steps, "
             "to t = %.4g s): nothing to report (a longer end_time? scripts/report.py shows "
             "where the rock went)" % (cpl_path, len(ct), ct[-1] if len(ct) else 0.0))
    t_hit = float(ct[hit[0]] - dataset(cpl, cpl_path, "steps/dt")[hit[0]])

    # impact: the block's velocity at its first contact with the net, from the last dem.h5
    # output step before it, carried to the contact with the acceleration of the two output
    # steps before (a block released on a slope, or at rest, reaches the net at its own speed)
    t_dem, v_block = block_velocity(dem, dem_path)
    k = max(int(np.searchsorted(t_dem, t_hit, side="right")) - 1, 0)
    v0 = v_block[k].copy()
    if k >= 1 and t_dem[k] > t_dem[k - 1]:
        v0 += (v_block[k] - v_block[k - 1]) / (t_dem[k] - t_dem[k - 1]) * (t_hit - t_dem[k])
    speed0 = float(np.linalg.norm(v0))
    if speed0 == 0.0:
        fail("%s: the block is at rest when it first touches the net (t = %.4g s)" % (dem_path, t_hit))
    d = v0 / speed0
    v_along = v_block @ d

    out = {"run": run, "steps": int(len(ct)), "unconverged_steps": int((conv == 0).sum()),
           "end_time_s": float(ct[-1]), "impact_speed_m_s": speed0,
           "impact_direction": [float(x) for x in d], "first_contact_s": t_hit}

    # elongation
    net = np.array(sets["net"])
    u = dataset(fem, fem_path, "output/displacement")
    t_out = dataset(fem, fem_path, "output/time")
    un = u[:, net, :] @ d
    k, j = np.unravel_index(np.argmax(un), un.shape)
    out["max_net_elongation_m"] = float(un[k, j])
    out["max_net_elongation_node"] = int(net[j])
    out["max_net_elongation_time_s"] = float(t_out[k])
    mon_ids = list(dataset(fem, fem_path, "monitor/node_ids"))
    centre = sets["net_centre"][0]
    if centre not in mon_ids:
        fail("%s: net_centre node %d is not a monitor node" % (fem_path, centre))
    mu = dataset(fem, fem_path, "monitor/displacement")[:, mon_ids.index(centre), :] @ d
    mt = dataset(fem, fem_path, "monitor/time")
    out["max_centre_elongation_m"] = float(mu.max())
    out["max_centre_elongation_time_s"] = float(mt[np.argmax(mu)])
    # where the net centre was when the block arrived: a barrier settling under its own weight
    # (make_barrier.py applies it at once) has sagged by then, which the figures above include
    at_contact = float(np.interp(t_hit, mt, mu))
    out["centre_at_contact_m"] = at_contact
    out["max_centre_elongation_from_contact_m"] = float(mu.max()) - at_contact

    # braking time
    after = t_dem > t_hit    # from the contact on, where the block moves at speed0 along d
    t_stop = first_crossing(np.concatenate(([t_hit], t_dem[after])),
                            np.concatenate(([speed0], v_along[after])))
    out["block_stop_s"] = t_stop
    out["braking_time_s"] = (t_stop - t_hit) if t_stop is not None else None
    out["block_final_velocity_along_m_s"] = float(v_along[-1])

    # residual height
    pos = dataset(fem, fem_path, "output/position")
    coords = np.array(model["nodes"], dtype=float)
    base_z = coords[sets["post_bases"], 2].mean()
    nominal = coords[sets["post_tops"], 2].mean() - base_z
    elements = dataset(fem, fem_path, "mesh/elements")
    eset = dataset(fem, fem_path, "mesh/element_set")
    supported = set(int(n) for n in dataset(fem, fem_path, "mesh/support_nodes"))
    if "top_rope" in names:
        top = sorted(set(elements[eset == names.index("top_rope")].ravel().tolist()) - supported)
    else:
        top = list(sets["post_tops"])
    z_end = pos[-1, top, 2] - base_z
    out["nominal_height_m"] = float(nominal)
    out["residual_height_m"] = float(z_end.min())
    out["residual_height_ratio"] = float(z_end.min() / nominal)
    out["residual_height_time_s"] = float(t_out[-1])

    # peak forces
    axial = dataset(fem, fem_path, "output/axial_force")
    peaks = {}
    for i, name in enumerate(names):
        sel = eset == i
        if sel.any():
            peaks[name] = {"type": types[i], "peak_axial_force_n": float(np.abs(axial[:, sel]).max())}
    out["peak_axial_force"] = peaks

    # overload: fem_solver's every-step peaks against the breaking loads (absent in older files)
    out["overload"] = None
    if "element_sets/peak_axial_force" in fem:
        es = lambda key: dataset(fem, fem_path, "element_sets/" + key)
        brk, peak, t_peak = es("breaking_load"), es("peak_axial_force"), es("peak_time")
        where, count, first = es("peak_element"), es("exceeded_elements"), es("first_exceedance_time")
        if len(brk) != len(names):
            fail("%s: element_sets has %d sets, %s %d" % (fem_path, len(brk), fem_json, len(names)))
        out["overload"] = {names[i]: {
            "breaking_load_n": float(brk[i]), "peak_axial_force_n": float(peak[i]),
            "ratio": float(peak[i] / brk[i]), "peak_time_s": float(t_peak[i]),
            "peak_element": int(where[i]), "exceeded_elements": int(count[i]),
            "first_exceedance_s": float(first[i]) if count[i] > 0 else None}
            for i in range(len(names)) if brk[i] > 0 and where[i] >= 0}
    reac = dataset(fem, fem_path, "output/reaction")
    snodes = list(dataset(fem, fem_path, "mesh/support_nodes"))
    rmag = np.linalg.norm(reac, axis=2)
    anchor_cols = [snodes.index(n) for n in sets["anchors"] if n in snodes]
    base_cols = [snodes.index(n) for n in sets["post_bases"] if n in snodes]
    out["peak_anchor_reaction_n"] = float(rmag[:, anchor_cols].max()) if anchor_cols else None
    out["peak_post_base_reaction_n"] = float(rmag[:, base_cols].max()) if base_cols else None

    # energy balance
    g = lambda key: dataset(cpl, cpl_path, "energy/" + key)
    dk = g("dem_kinetic")
    k_hit = max(hit[0] - 1, 0)
    dem_diss = g("dem_dissipated")
    brake = dataset(fem, fem_path, "output/element_dissipated_energy")[-1].sum() \
        if "output/element_dissipated_energy" in fem else 0.0
    fem_diss = float(g("fem_dissipated").sum())
    out["energy"] = {
        "block_kinetic_at_contact_j": float(dk[k_hit]),
        "block_kinetic_end_j": float(dk[-1]),
        "brakes_j": float(brake),
        "fem_other_dissipation_j": fem_diss - float(brake),
        "fem_strain_end_j": float(g("fem_elastic")[-1]),
        "fem_kinetic_end_j": float(g("fem_kinetic")[-1]),
        "contact_dissipation_j": float(dem_diss[hit[0]:].sum()),
        "dissipation_before_contact_j": float(dem_diss[:hit[0]].sum()),
        "interface_mismatch_j": float(g("interface_created").sum()),
        "created_max_j": float(g("created").max()),
        "created_limit_j": float(g("limit")[-1]),
        "guard_fired": bool(g("above").any()),
    }
    if "energy/dem_potential" in cpl:   # the block climbing after the rebound (a slope)
        dp = g("dem_potential")
        out["energy"]["block_potential_change_j"] = float(dp[-1] - dp[k_hit])
    # the integrator's share of the FEM's dissipation (coupling.h5 from the version that
    # records it): what no physical mechanism of the model (brakes, Rayleigh damping, contact
    # dashpots) accounts for, together with the interface mismatch
    numerical = cpl["energy/fem_numerical_dissipated"][()] if "energy/fem_numerical_dissipated" in cpl else None
    if numerical is not None and np.isfinite(numerical).all():
        e = out["energy"]
        e["fem_numerical_dissipation_j"] = float(numerical.sum())
        e["fem_rayleigh_dissipation_j"] = e["fem_other_dissipation_j"] - e["fem_numerical_dissipation_j"]
        e["unattributed_j"] = e["fem_numerical_dissipation_j"] - e["interface_mismatch_j"]
        e["unattributed_ratio"] = e["unattributed_j"] / e["block_kinetic_at_contact_j"]
    # force-time curves (output steps): the largest |N| of each set, the largest anchor reaction
    forces = {name: np.abs(axial[:, eset == i]).max(axis=1) for i, name in enumerate(names)
              if (eset == i).any()}
    if anchor_cols:
        forces["anchor reaction"] = rmag[:, anchor_cols].max(axis=1)
    return out, (mt, mu, t_dem, v_along, ct, g, t_out, forces)


def print_report(r):
    p = print
    p("barrier report: %s" % r["run"])
    p("  run: %d steps to t = %.4g s, %d unconverged" % (r["steps"], r["end_time_s"], r["unconverged_steps"]))
    p("  impact: %.3g m/s along (%.3f, %.3f, %.3f) at the first contact with the net, %.4g s"
      % ((r["impact_speed_m_s"],) + tuple(r["impact_direction"]) + (r["first_contact_s"],)))
    p("  maximum elongation: net %.3f m (node %d, t = %.4g s; fem.h5 output steps only), "
      "net_centre %.3f m (t = %.4g s; every step), from the model's geometry; net_centre "
      "from where it was at the first contact: %.3f m (it had moved %.3f m by then, its sag "
      "under its own weight)"
      % (r["max_net_elongation_m"], r["max_net_elongation_node"], r["max_net_elongation_time_s"],
         r["max_centre_elongation_m"], r["max_centre_elongation_time_s"],
         r["max_centre_elongation_from_contact_m"], r["centre_at_contact_m"]))
    if r["braking_time_s"] is None:
        p("  braking time: the block did not stop (velocity along the impact direction at the end "
          "%.3g m/s; dem.h5 output steps)" % r["block_final_velocity_along_m_s"])
    else:
        p("  braking time: %.4g s (stopped at %.4g s, dem.h5 output steps interpolated); final "
          "velocity along the impact direction %.3g m/s"
          % (r["braking_time_s"], r["block_stop_s"], r["block_final_velocity_along_m_s"]))
    p("  residual height: %.3f m of nominal %.3f m (%.1f %%; lowest top-rope node at t = %.4g s)"
      % (r["residual_height_m"], r["nominal_height_m"], 100 * r["residual_height_ratio"],
         r["residual_height_time_s"]))
    p("  peak axial forces (fem.h5 output steps only):")
    for name, v in r["peak_axial_force"].items():
        p("    %-14s %-14s %10.4g kN" % (name, v["type"], v["peak_axial_force_n"] / 1e3))
    if r["overload"] is not None:
        p("  breaking loads (fem.h5 /element_sets, every FEM step):")
        for name, v in r["overload"].items():
            p("    %-14s peak %8.4g kN / breaking load %8.4g kN = %.2fx (element %d, t = %.4g s)%s"
              % (name, v["peak_axial_force_n"] / 1e3, v["breaking_load_n"] / 1e3, v["ratio"],
                 v["peak_element"], v["peak_time_s"],
                 "; %d elements EXCEEDED it, first at t = %.4g s" % (v["exceeded_elements"], v["first_exceedance_s"])
                 if v["exceeded_elements"] else ""))
        if any(v["exceeded_elements"] for v in r["overload"].values()):
            p("    the model has no rope failure: forces beyond the breaking load are not physical")
    p("  peak reaction: anchors %.4g kN, post bases %.4g kN (output steps only)"
      % ((r["peak_anchor_reaction_n"] or 0) / 1e3, (r["peak_post_base_reaction_n"] or 0) / 1e3))
    e = r["energy"]
    p("  energy (coupling.h5 /energy, every step; brakes from fem.h5):")
    p("    block kinetic (translation and rotation) at contact %.4g J -> end %.4g J%s"
      % (e["block_kinetic_at_contact_j"], e["block_kinetic_end_j"],
         "; its potential energy from contact to the end %+.4g J" % e["block_potential_change_j"]
         if "block_potential_change_j" in e else ""))
    p("    brakes %.4g J, other FEM dissipation (Rayleigh, integrator) %.4g J, contact %.4g J "
      "(the DEM's dissipation from the first net contact on; before it, on terrain or walls: %.4g J)"
      % (e["brakes_j"], e["fem_other_dissipation_j"], e["contact_dissipation_j"],
         e["dissipation_before_contact_j"]))
    p("    structure at the end: strain %.4g J, kinetic %.4g J; interface mismatch %.4g J"
      % (e["fem_strain_end_j"], e["fem_kinetic_end_j"], e["interface_mismatch_j"]))
    p("    created (largest) %.4g J, guard limit %.4g J: %s"
      % (e["created_max_j"], e["created_limit_j"], "FIRED" if e["guard_fired"] else "silent"))
    if "unattributed_j" in e:
        p("    of the other FEM dissipation: Rayleigh damping %.4g J, the integrator %.4g J; not "
          "attributed to a mechanism of the model (integrator + interface mismatch): %.4g J, "
          "%.2g %% of the block's kinetic energy at contact"
          % (e["fem_rayleigh_dissipation_j"], e["fem_numerical_dissipation_j"], e["unattributed_j"],
             100 * e["unattributed_ratio"]))


def plot(r, series, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    mt, mu, t_dem, v_along, ct, g, t_out, forces = series
    fig, ax = plt.subplots(4, 1, figsize=(7, 11.5), sharex=True)
    ax[0].plot(mt, mu)
    ax[0].set_ylabel("net_centre along impact (m)")
    ax[1].plot(t_dem, v_along, "o-")
    ax[1].set_ylabel("block velocity along impact (m/s)")
    for key in ("dem_kinetic", "fem_kinetic", "fem_elastic"):
        ax[2].plot(ct, g(key), label=key)
    ax[2].plot(ct, np.cumsum(g("fem_dissipated")), label="fem dissipated")
    ax[2].plot(ct, np.cumsum(g("dem_dissipated")), label="contact dissipated")
    ax[2].set_ylabel("energy (J)")
    ax[2].legend()
    for name, f in forces.items():
        ax[3].plot(t_out, f / 1e3, label=name)
    ax[3].set_ylabel("largest force (kN, output steps)")
    ax[3].set_xlabel("t (s)")
    ax[3].legend(fontsize=8, ncol=2)
    fig.tight_layout()
    fig.savefig(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", help="run folder (scripts/run_case.sh --out)")
    ap.add_argument("--json", help="also write the figures as JSON here")
    ap.add_argument("--plot", help="draw elongation, block velocity, energies and forces to this image")
    a = ap.parse_args()
    r, series = report(a.run)
    print_report(r)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(r, fh, indent=1)
    if a.plot:
        plot(r, series, a.plot)


if __name__ == "__main__":
    main()
