#!/usr/bin/python3
"""make_barrier — a flexible rockfall barrier as a fem_solver model (fem.json) from a few
parameters, and a short summary of what it wrote (topology counts, masses, rope and brake
parameters, where the defaults come from).

Geometry (x along the barrier, y downslope = the impact direction, z up):
- posts at x_k = k * spacing (k = 0..modules), hinged at their base (x_k, 0, 0) (a pin: all
  three dofs fixed), top at base + height * (0, sin t, cos t), t = --tilt-deg (positive:
  tops leaning downslope); type `post`;
- the net spans all modules between the bottom (z = 0) and the top (the post tops), in the
  plane of the posts: a square grid of about --mesh-size (an integer number of meshes per
  module and over the height); type `cable` (`--net wire_rope`, wire-rope mesh) or `ring`
  (`--net ring`). Its border is the ropes: the top and bottom rows are shackle nodes on the
  support ropes, the end columns are held by the edge ropes; the net nodes on the post
  columns are the post tops (top row) and post bases (bottom row);
- top and bottom support ropes: each one `sliding_cable` from a brake at the left anchor,
  over / through the end post, through every shackle node of its net edge (over the
  interior post tops, through the post bases) to a brake at the right anchor. Top-rope
  anchors at (x_end -/+ height, 0, 0), bottom-rope anchors at (x_end -/+ height/2, 0, 0);
  each brake (type `brake`, --brake-length long) lies on the rope's line at the anchor;
- upslope (retaining) ropes: from each post top to an anchor at (x_k, -upslope distance, 0),
  the rope and its brake in series as one `brake` element (stiffness 1/(1/k_e + L/EA));
- lateral ropes: from each end post top to a lateral anchor at (x_end -/+ 0.75 height, 0, 0)
  (in the barrier's plane, so they hold the end post along the barrier without pulling it
  upslope), a cable; and the edge ropes: a `sliding_cable` from each end post top down
  through the net's end column to the post base;
- on every sliding rope two neighbouring nodes stop --shackle-gap apart (fem_solver's shackle
  contact, `shackle_gap_m`).

Named node sets: anchors (all), anchor_top_rope, anchor_bottom_rope, anchor_upslope,
anchor_lateral, post_bases, post_tops, net (all net nodes), net_centre (the node nearest the
centre of the middle module, where a test block is aimed), module_centres (one per module),
top_shackles, bottom_shackles. Supports: anchors and post bases, xyz. Interface (for the DEM):
the net's elements only. Monitor nodes: net_centre, then the post tops.

Defaults: a three-module barrier, 10 m post spacing, 4 m high, the 100–500 kJ class; see the
summary it writes and README.md ("Barriers") for their provenance (project estimates where no
published value was available here).

    scripts/make_barrier.py --output fem.json --summary barrier.md
    scripts/make_barrier.py --modules 1 --net ring --analysis static --output fem.json
"""
import argparse
import json
import math
import os
import sys

STEEL_E = 1.0e11          # rope modulus (steel rope, project standard)
STEEL_RHO = 7850.0
G = 9.81


def repo_relative(arg):
    """A path inside the repository as seen from its root (the summary does not name the
    machine it was written on); anything else unchanged."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    if os.path.isabs(arg) and os.path.commonpath([root, arg]) == root:
        return os.path.relpath(arg, root)
    return arg


def rope_area(d, f=0.58):
    """Metallic area of a six-strand steel-core rope of nominal diameter d: f pi d^2 / 4
    (f = 0.58, EN 12385-4, as fem_solver's metallic_area_factor default)."""
    return f * math.pi * d * d / 4.0


def parse_args(argv):
    p = argparse.ArgumentParser(
        prog="make_barrier.py",
        description="make_barrier — a flexible rockfall barrier (posts, net, support, upslope, "
                    "lateral and edge ropes, brakes) as a fem_solver fem.json. x along the "
                    "barrier, y downslope (impact direction), z up.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    g = p.add_argument_group("geometry")
    g.add_argument("--modules", type=int, default=3, help="number of modules (fields between posts)")
    g.add_argument("--spacing", type=float, default=10.0, help="post spacing (m)")
    g.add_argument("--height", type=float, default=4.0, help="nominal height = post length (m)")
    g.add_argument("--tilt-deg", type=float, default=10.0,
                   help="post tilt about the barrier axis, tops downslope (deg); > 0 keeps the "
                        "upslope ropes taut under self-weight")
    g.add_argument("--upslope-distance", type=float, default=None,
                   help="upslope anchor distance from the post base (m, default = height)")
    n = p.add_argument_group("net")
    n.add_argument("--net", choices=("wire_rope", "ring"), default="wire_rope", help="net type")
    n.add_argument("--mesh-size", type=float, default=0.3, help="net mesh size (m)")
    n.add_argument("--net-rope-diameter", type=float, default=0.008,
                   help="wire_rope: rope diameter of the mesh (m)")
    n.add_argument("--net-pretension", type=float, default=50.0,
                   help="wire_rope: pretension of each mesh rope (N)")
    n.add_argument("--ring-wire-diameter", type=float, default=0.003, help="ring: wire diameter (m)")
    n.add_argument("--ring-windings", type=int, default=7, help="ring: windings per ring")
    n.add_argument("--ring-bending-force", type=float, default=5.0e3,
                   help="ring: force at the end of the bending phase (N)")
    r = p.add_argument_group("ropes")
    r.add_argument("--support-rope-diameter", type=float, default=0.022, help="top and bottom support ropes (m)")
    r.add_argument("--support-pretension", type=float, default=1.0e4, help="support rope pretension (N)")
    r.add_argument("--upslope-rope-diameter", type=float, default=0.018, help="upslope ropes (m)")
    r.add_argument("--lateral-rope-diameter", type=float, default=0.018, help="lateral ropes (m)")
    r.add_argument("--lateral-pretension", type=float, default=2.0e3, help="lateral rope pretension (N)")
    r.add_argument("--edge-rope-diameter", type=float, default=0.016, help="edge ropes (m)")
    r.add_argument("--edge-pretension", type=float, default=5.0e3, help="edge rope pretension (N)")
    r.add_argument("--rope-modulus", type=float, default=STEEL_E, help="E of every rope (Pa)")
    r.add_argument("--shackle-gap", type=float, default=0.05,
                   help="sliding ropes: the closest two neighbouring shackles (or a shackle and a "
                        "post top or anchor) come along the rope (m; 0: no contact)")
    b = p.add_argument_group("brakes")
    b.add_argument("--brake-length", type=float, default=1.0, help="brake length (m)")
    b.add_argument("--brake-elastic-stiffness", type=float, default=5.0e6, help="k_e (N/m)")
    b.add_argument("--support-brake-force", type=float, default=4.0e4, help="support-rope brakes F_a (N)")
    b.add_argument("--upslope-brake-force", type=float, default=3.0e4, help="upslope-rope brakes F_a (N)")
    b.add_argument("--brake-hardening", type=float, default=1.0e4, help="k_h (N/m)")
    b.add_argument("--brake-stroke", type=float, default=1.0, help="s_max (m)")
    b.add_argument("--brake-locking-stiffness", type=float, default=5.0e7, help="k_lock (N/m)")
    b.add_argument("--brake-mass", type=float, default=8.0, help="mass of one brake (kg)")
    s = p.add_argument_group("posts")
    s.add_argument("--post-area", type=float, default=3.88e-3, help="post section area (m^2; HEA 160)")
    s.add_argument("--post-modulus", type=float, default=2.1e11, help="post E (Pa)")
    a = p.add_argument_group("analysis")
    a.add_argument("--analysis", choices=("dynamic", "static"), default="dynamic")
    a.add_argument("--load-steps", type=int, default=5, help="static: load steps")
    a.add_argument("--dt", type=float, default=1e-3, help="dynamic: time step (s)")
    a.add_argument("--end-time", type=float, default=1.0, help="dynamic: end time (s)")
    a.add_argument("--initial-state", choices=("static", "reference"), default="static",
                   help="dynamic: start at rest in static equilibrium under self-weight and "
                        "pretension (static), or at the generated geometry, sagging and swinging "
                        "from t = 0 on (reference)")
    # the damping defaults are the MEL test's recipe (cases/barrier_mel/README.md): the ropes,
    # not the integrator, damp the light net's highest modes
    a.add_argument("--alpha-b", type=float, default=-0.1, help="dynamic: Bossak alpha")
    a.add_argument("--rayleigh-tau", type=float, default=2.0, help="mass-proportional damping (1/s)")
    a.add_argument("--rayleigh-kappa", type=float, default=1e-4,
                   help="stiffness-proportional damping of every element (s): the ropes' internal "
                        "friction, a damping ratio kappa w / 2 at a frequency w")
    a.add_argument("--output-interval", type=int, default=10, help="full output every N steps")
    o = p.add_argument_group("output")
    o.add_argument("--output", required=True, help="fem.json to write")
    o.add_argument("--summary", help="also write the summary (Markdown) here")
    args = p.parse_args(argv)
    for name in ("spacing", "height", "mesh_size", "brake_length", "net_rope_diameter",
                 "support_rope_diameter", "upslope_rope_diameter", "lateral_rope_diameter",
                 "edge_rope_diameter", "rope_modulus", "brake_elastic_stiffness",
                 "support_brake_force", "upslope_brake_force", "brake_stroke",
                 "brake_locking_stiffness", "post_area", "post_modulus", "dt", "end_time",
                 "ring_wire_diameter", "ring_bending_force"):
        if not getattr(args, name) > 0:
            p.error("--%s: expected a number > 0, got %r" % (name.replace("_", "-"), getattr(args, name)))
    if not 0 <= args.shackle_gap < 0.5 * args.mesh_size:
        p.error("--shackle-gap: expected 0 <= gap < half the mesh size (%g m), got %r"
                % (0.5 * args.mesh_size, args.shackle_gap))
    if args.modules < 1:
        p.error("--modules: expected an integer >= 1, got %d" % args.modules)
    if not -45.0 < args.tilt_deg < 45.0:
        p.error("--tilt-deg: expected a value in (-45, 45), got %r" % args.tilt_deg)
    if args.mesh_size > min(args.spacing, args.height) / 2:
        p.error("--mesh-size: %g m leaves fewer than 2 meshes per module or over the height" % args.mesh_size)
    if args.brake_length >= args.height / 2:
        p.error("--brake-length: %g m is too long for a %g m high barrier" % (args.brake_length, args.height))
    if args.upslope_distance is None:
        args.upslope_distance = args.height
    return args


class Builder:
    """Nodes, elements (with their set), node sets."""

    def __init__(self):
        self.nodes, self.elements, self.node_sets = [], [], {}

    def node(self, xyz):
        self.nodes.append([float(round(c, 12)) + 0.0 for c in xyz])
        return len(self.nodes) - 1

    def element(self, k, l, set_name):
        assert k != l
        self.elements.append({"nodes": [k, l], "set": set_name})

    def chain(self, ids, set_name):
        for k, l in zip(ids[:-1], ids[1:]):
            self.element(k, l, set_name)


def add(a, b, s=1.0):
    return [a[i] + s * b[i] for i in range(3)]


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def unit(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def dist(a, b):
    return math.sqrt(sum((a[i] - b[i]) ** 2 for i in range(3)))


def build(args):
    """Return (fem dict, info dict) for the parameters."""
    M, s, h = args.modules, args.spacing, args.height
    t = math.radians(args.tilt_deg)
    axis = [0.0, math.sin(t), math.cos(t)]            # post direction
    per_module = max(2, int(round(s / args.mesh_size)))
    rows = max(2, int(round(h / args.mesh_size)))      # meshes over the height
    nx, nz = M * per_module + 1, rows + 1
    dx, dz = s / per_module, h / rows
    B = Builder()

    # net grid (i along x, j up the posts): node (i, j) = base(x_i) + j dz axis
    grid = [[B.node(add([i * dx, 0.0, 0.0], axis, j * dz)) for j in range(nz)] for i in range(nx)]
    post_cols = [k * per_module for k in range(M + 1)]
    bases = [grid[c][0] for c in post_cols]
    tops = [grid[c][nz - 1] for c in post_cols]
    X = lambda i: B.nodes[i]

    net_set = "net"
    for j in range(1, nz - 1):                      # horizontal meshes (not the top/bottom rows)
        for i in range(nx - 1):
            B.element(grid[i][j], grid[i + 1][j], net_set)
    for i in range(1, nx - 1):                      # vertical meshes (not the end columns)
        for j in range(nz - 1):
            B.element(grid[i][j], grid[i][j + 1], net_set)
    n_net_elements = len(B.elements)

    for k in range(M + 1):
        B.element(bases[k], tops[k], "post")

    anchors = {"anchor_top_rope": [], "anchor_bottom_rope": [], "anchor_upslope": [], "anchor_lateral": []}
    lb = args.brake_length
    x_end = [0.0, M * s]
    sign = [-1.0, 1.0]

    def braked_end(anchor_xyz, towards_xyz, anchor_set):
        """Anchor node and brake end node lb from it towards towards_xyz; the brake element."""
        a = B.node(anchor_xyz)
        e = B.node(add(anchor_xyz, unit(sub(towards_xyz, anchor_xyz)), lb))
        anchors[anchor_set].append(a)
        return a, e

    def support_rope(row_nodes, anchor_dx, set_name, anchor_set):
        left_a, left_e = braked_end([x_end[0] - anchor_dx, 0.0, 0.0], X(row_nodes[0]), anchor_set)
        right_a, right_e = braked_end([x_end[1] + anchor_dx, 0.0, 0.0], X(row_nodes[-1]), anchor_set)
        B.element(left_a, left_e, "brake_support")
        B.chain([left_e] + row_nodes + [right_e], set_name)
        B.element(right_e, right_a, "brake_support")

    top_row = [grid[i][nz - 1] for i in range(nx)]
    bottom_row = [grid[i][0] for i in range(nx)]
    support_rope(top_row, h, "top_rope", "anchor_top_rope")
    support_rope(bottom_row, h / 2.0, "bottom_rope", "anchor_bottom_rope")

    for k in range(M + 1):                          # upslope ropes: rope and brake in series
        a = B.node([k * s, -args.upslope_distance, 0.0])
        anchors["anchor_upslope"].append(a)
        B.element(a, tops[k], "upslope_rope")
    for side in (0, 1):                             # lateral ropes, edge ropes
        top = tops[0] if side == 0 else tops[-1]
        a = B.node([x_end[side] + sign[side] * 0.75 * h, 0.0, 0.0])
        anchors["anchor_lateral"].append(a)
        B.element(top, a, "lateral_rope")
    for side in (0, 1):
        col = 0 if side == 0 else nx - 1
        B.chain([grid[col][j] for j in range(nz - 1, -1, -1)], "edge_rope")

    # the middle module's centre
    mid = M // 2
    cx = (mid + 0.5) * s
    centre_i = int(round(cx / dx))
    centre_j = int(round((h / 2.0) / dz))
    module_centres = [grid[int(round((k + 0.5) * s / dx))][centre_j] for k in range(M)]
    net_centre = grid[centre_i][centre_j]

    all_anchors = sum(anchors.values(), [])
    B.node_sets.update(anchors)
    B.node_sets.update({
        "anchors": all_anchors, "post_bases": bases, "post_tops": tops,
        "net": [grid[i][j] for j in range(nz) for i in range(nx)],
        "net_centre": [net_centre], "module_centres": module_centres,
        "top_shackles": [n for n in top_row if n not in tops],
        "bottom_shackles": [n for n in bottom_row if n not in bases],
    })

    # element sets
    E = args.rope_modulus
    def rope(name, d, pre, typ):
        r = {"name": name, "type": typ, "youngs_modulus_pa": E, "diameter_m": d,
             "density_kg_m3": STEEL_RHO, "pretension_n": pre, "breaking_load_n": breaking_load(d)}
        if typ == "sliding_cable" and args.shackle_gap > 0:
            r["shackle_gap_m"] = args.shackle_gap
        return r
    sets = []
    if args.net == "wire_rope":
        d = args.net_rope_diameter
        sets.append({"name": net_set, "type": "cable", "youngs_modulus_pa": E, "diameter_m": d,
                     "density_kg_m3": STEEL_RHO, "pretension_n": args.net_pretension,
                     "breaking_load_n": breaking_load(d), "behaviour": "cable"})
    else:
        sets.append(ring_set(args, dx, dz))
    sets += [
        rope("top_rope", args.support_rope_diameter, args.support_pretension, "sliding_cable"),
        rope("bottom_rope", args.support_rope_diameter, args.support_pretension, "sliding_cable"),
        rope("edge_rope", args.edge_rope_diameter, args.edge_pretension, "sliding_cable"),
        rope("lateral_rope", args.lateral_rope_diameter, args.lateral_pretension, "cable"),
        {"name": "post", "type": "post", "youngs_modulus_pa": args.post_modulus,
         "area_m2": args.post_area, "density_kg_m3": STEEL_RHO},
    ]
    brake_area = args.brake_mass / (STEEL_RHO * lb)
    sets.append({"name": "brake_support", "type": "brake",
                 "elastic_stiffness_n_per_m": args.brake_elastic_stiffness,
                 "activation_force_n": args.support_brake_force,
                 "hardening_stiffness_n_per_m": args.brake_hardening, "max_stroke_m": args.brake_stroke,
                 "locking_stiffness_n_per_m": args.brake_locking_stiffness,
                 "area_m2": brake_area, "density_kg_m3": STEEL_RHO})
    # An upslope rope and its brake in series as one brake element from the anchor to the post
    # top: elastic stiffness 1 / (1/k_e + L/EA), the rope's mass plus the brake's. (A separate
    # node between a rope and a brake has no transverse stiffness while the rope is slack,
    # which makes the static problem singular whenever nothing pulls the post downslope.)
    L_up = dist(X(anchors["anchor_upslope"][0]), X(tops[0]))
    A_up = rope_area(args.upslope_rope_diameter)
    k_up = 1.0 / (1.0 / args.brake_elastic_stiffness + L_up / (E * A_up))
    lock_up = 1.0 / (1.0 / args.brake_locking_stiffness + L_up / (E * A_up))
    sets.append({"name": "upslope_rope", "type": "brake", "elastic_stiffness_n_per_m": k_up,
                 "activation_force_n": args.upslope_brake_force,
                 "hardening_stiffness_n_per_m": args.brake_hardening, "max_stroke_m": args.brake_stroke,
                 "locking_stiffness_n_per_m": lock_up,
                 "area_m2": A_up + args.brake_mass / (STEEL_RHO * L_up), "density_kg_m3": STEEL_RHO})
    sets.sort(key=lambda st: ["net", "top_rope", "bottom_rope", "edge_rope", "upslope_rope",
                              "lateral_rope", "post", "brake_support"].index(st["name"]))

    analysis = {"type": args.analysis, "max_iterations": 40}
    if args.analysis == "static":
        analysis["load_steps"] = args.load_steps
    else:
        analysis.update({"integrator": "bossak", "alpha_b": args.alpha_b, "dt_s": args.dt,
                         "end_time_s": args.end_time, "initial_state": args.initial_state})

    # masses per set, by hand from the geometry
    masses, lengths = {}, {}
    for st in sets:
        L = sum(dist(X(e["nodes"][0]), X(e["nodes"][1])) for e in B.elements if e["set"] == st["name"])
        A = st.get("area_m2") or rope_area(st["diameter_m"])
        lengths[st["name"]] = L
        masses[st["name"]] = st["density_kg_m3"] * A * L
    normal = [0.0, math.cos(t), -math.sin(t)]        # net normal, downslope
    info = {
        "modules": M, "nx": nx, "nz": nz, "dx": dx, "dz": dz, "per_module": per_module,
        "net_elements": n_net_elements, "masses": masses, "lengths": lengths,
        "net_centre": net_centre, "net_centre_xyz": X(net_centre), "normal": normal,
        "counts": {st["name"]: sum(1 for e in B.elements if e["set"] == st["name"]) for st in sets},
        "anchors": len(all_anchors), "brakes": sum(1 for e in B.elements if e["set"].startswith("brake")),
    }
    desc = ("Rockfall barrier from scripts/make_barrier.py: %d module(s) of %g m, %g m high, posts "
            "tilted %g deg downslope, %s net at %.3g x %.3g m (%d x %d nodes), support ropes %g mm "
            "(sliding, brakes %g kN at both ends), upslope ropes %g mm with brakes %g kN, lateral and "
            "edge ropes; anchors and post bases pinned. Impact target: node %d (%s), net normal %s."
            % (M, s, h, args.tilt_deg, args.net, dx, dz, nx, nz, 1000 * args.support_rope_diameter,
               args.support_brake_force / 1000, 1000 * args.upslope_rope_diameter,
               args.upslope_brake_force / 1000, net_centre,
               ", ".join("%.3f" % c for c in X(net_centre)), ", ".join("%.3f" % c for c in normal)))
    fem = {
        "description": desc,
        "nodes": B.nodes,
        "elements": B.elements,
        "element_sets": sets,
        "node_sets": B.node_sets,
        "supports": [{"nodes": ["anchors", "post_bases"], "dofs": "xyz"}],
        "self_weight": True,
        "gravity_m_s2": [0.0, 0.0, -G],
        "mass": "consistent",
        "rayleigh": {"tau_per_s": args.rayleigh_tau, "kappa_s": args.rayleigh_kappa},
        "interface": {"element_sets": [net_set]},
        "monitor_nodes": ["net_centre", "post_tops"],
        "output": {"interval_steps": args.output_interval},
        "analysis": analysis,
    }
    return fem, info


def breaking_load(d):
    """Minimum breaking force of a six-strand steel-core rope of grade 1770 (N): about
    0.64 kN per mm^2 of nominal d^2 (K' R_r d^2 with the EN 12385-4 factor K' ~ 0.36 and
    R_r = 1770 N/mm^2)."""
    return 0.36 * 1770.0 * (d * 1000.0) ** 2


def ring_set(args, dx, dz):
    """Ring net: one ring per node of diameter D = mesh size (touching rings), a connection
    between neighbours is a `ring` element. delta_m: a ring pulled across goes from its
    diameter D to half its circumference, an elongation D (pi/2 - 1) over the two half rings
    of a connection; k_m: the two straight strands of the wire bundle (windings x wire area,
    E of the rope modulus) over half the circumference; k_b: the bending-phase force
    --ring-bending-force reached at delta_m. Mass: each ring (pi D windings of wire) shared
    by its two connections of length D... (per unit length ring mass / (2 D))."""
    D = 0.5 * (dx + dz)
    wire = math.pi * args.ring_wire_diameter ** 2 / 4.0
    bundle = args.ring_windings * wire
    dm = D * (math.pi / 2.0 - 1.0)
    km = args.rope_modulus * 2.0 * bundle / (math.pi * D / 2.0)
    kb = args.ring_bending_force / dm
    ring_mass = STEEL_RHO * bundle * math.pi * D
    return {"name": "net", "type": "ring", "bending_stiffness_n_per_m": kb,
            "membrane_stiffness_n_per_m": max(km, kb), "membrane_elongation_m": dm,
            "area_m2": ring_mass / (2.0 * D * STEEL_RHO), "density_kg_m3": STEEL_RHO}


def summary(args, fem, info):
    sets = {st["name"]: st for st in fem["element_sets"]}
    total = sum(info["masses"].values())
    lines = ["# Barrier model (scripts/make_barrier.py)", "",
             "Command: `scripts/make_barrier.py %s`" % " ".join(map(repo_relative, sys.argv[1:])), "",
             "## Topology", "",
             "- %d module(s), post spacing %g m, height %g m, tilt %g deg downslope" %
             (args.modules, args.spacing, args.height, args.tilt_deg),
             "- %d nodes, %d elements; net %s %d x %d nodes, mesh %.4g m x %.4g m; %d anchors, %d brakes" %
             (len(fem["nodes"]), len(fem["elements"]), args.net, info["nx"], info["nz"],
              info["dx"], info["dz"], info["anchors"], info["brakes"]),
             "- impact target `net_centre`: node %d at (%s) m, net normal (%s)" %
             (info["net_centre"], ", ".join("%.3f" % c for c in info["net_centre_xyz"]),
              ", ".join("%.3f" % c for c in info["normal"])), "",
             "| set | type | elements | length (m) | mass (kg) | parameters |",
             "|---|---|---|---|---|---|"]
    for name, st in sets.items():
        if st["type"] == "brake":
            par = "F_a %.4g kN, k_e %.3g N/m, k_h %.3g N/m, stroke %g m, k_lock %.3g N/m" % (
                st["activation_force_n"] / 1e3, st["elastic_stiffness_n_per_m"],
                st["hardening_stiffness_n_per_m"], st["max_stroke_m"], st["locking_stiffness_n_per_m"])
        elif st["type"] == "ring":
            par = "k_b %.3g N/m, k_m %.3g N/m, delta_m %.3g m" % (
                st["bending_stiffness_n_per_m"], st["membrane_stiffness_n_per_m"], st["membrane_elongation_m"])
        elif st["type"] == "post":
            par = "E %.3g Pa, A %.4g m^2" % (st["youngs_modulus_pa"], st["area_m2"])
        else:
            par = "d %g mm, E %.3g Pa, pretension %.4g kN, breaking load %.0f kN" % (
                1e3 * st["diameter_m"], st["youngs_modulus_pa"], st["pretension_n"] / 1e3,
                st["breaking_load_n"] / 1e3)
            if "shackle_gap_m" in st:
                par += ", shackle gap %g m" % st["shackle_gap_m"]
        lines.append("| %s | %s | %d | %.4g | %.4g | %s |" % (
            name, st["type"], info["counts"][name], info["lengths"][name], info["masses"][name], par))
    start = ""
    if fem["analysis"]["type"] == "dynamic":
        start = (" The dynamic run starts at rest in static equilibrium under self-weight and "
                 "pretension (analysis.initial_state \"static\"): the net hangs still until the "
                 "rock strikes it." if args.initial_state == "static" else
                 " The dynamic run starts at the generated geometry (analysis.initial_state "
                 "\"reference\"): the net falls into its sag and swings from t = 0 on.")
    lines += ["", "Total mass %.1f kg (weight %.4g kN).%s" % (total, total * G / 1e3, start), "",
              "## Where the default values come from", "",
              "The defaults describe a barrier of the 100-500 kJ class as the project estimates it; "
              "they are not one manufacturer's data and no certified system's values were "
              "available here. Fit them to the barrier at hand:",
              "- ropes: six-strand steel-core ropes, metallic area 0.58 pi d^2/4 (EN 12385-4 fill "
              "factor, fem_solver's default), E 1e11 Pa by default (the project's rope modulus; "
              "this model: %g Pa), minimum "
              "breaking force of grade 1770 about 0.36 x 1770 N/mm^2 x d^2 (EN 12385-4 form); "
              "diameters 8 mm (net), 16-22 mm (edge, upslope, lateral, support ropes) are the usual "
              "range of such barriers (project estimate);" % args.rope_modulus,
              "- brakes: the bilinear elastic-plastic law with a stroke limit (fem_solver README, "
              "after Volkwein, Diss. ETH Zurich 15641, 2004, and Gentilini et al., Engineering "
              "Structures 50, 2013); activation forces 30-40 kN, stroke 1 m are project estimates "
              "to be fitted to a manufacturer's force-stroke curve;",
              "- posts: an HEA 160 section (A 38.8 cm^2, 30.5 kg/m), hinged at the base;",
              "- damping (dynamic): by default Rayleigh tau 2 1/s, kappa 1e-4 s on every element "
              "and Bossak alpha -0.1, the MEL test's recipe (cases/barrier_mel/README.md): the "
              "ropes, not the integrator, damp the light net's highest modes (what no mechanism of "
              "the model accounts for: 0.36 %% of the small barrier test's impact energy against "
              "0.9 %% with Bossak -0.3 alone); kappa is a project estimate, not a measured rope "
              "property (this model: tau %g 1/s, kappa %g s, Bossak %g);"
              % (args.rayleigh_tau, args.rayleigh_kappa, args.alpha_b),
              "- shackles: two neighbours on a sliding rope (or a shackle and a post top or anchor) "
              "stop %g m apart (--shackle-gap; the default 5 cm is about the size of a shackle for "
              "these ropes, a project estimate), with the contact stiffness EA / gap (fem_solver's "
              "default);" % args.shackle_gap,
              "- ring net (`--net ring`): rings of diameter = mesh size with --ring-windings "
              "windings of --ring-wire-diameter wire; membrane elongation D (pi/2 - 1) and stiffness "
              "of the two strands are derived from that geometry, the bending-phase force is an "
              "estimate (fit k_b, delta_m, k_m to a tensile test of the net).",
              "", "The net is one grid over all modules (the real panels of a module are joined at "
              "the posts by the support ropes; here the meshes run past the interior posts), "
              "shackles slide without friction, posts carry no bending."]
    return "\n".join(lines) + "\n"


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    fem, info = build(args)
    try:
        for path in (args.output, args.summary):   # their folders too, as run_case.sh's --out
            if path and os.path.dirname(path):
                os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(args.output, "w") as f:
            json.dump(fem, f, indent=1)
            f.write("\n")
        text = summary(args, fem, info)
        if args.summary:
            with open(args.summary, "w") as f:
                f.write(text)
    except OSError as e:
        print("make_barrier.py: %s: %s" % (e.filename, e.strerror), file=sys.stderr)
        return 1
    print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
