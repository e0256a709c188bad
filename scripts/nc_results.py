"""Reading netcouple results (fem.h5, dem.h5, coupling.h5) for plots and checks.

Only the dataset names that the programs document as stable are used:
fem.h5   /monitor/time, /monitor/node_ids, /monitor/displacement (steps x nodes x 3),
         /output/{time,axial_force,strain,reaction,displacement,position},
         /mesh/{support_nodes,coordinates,elements,reference_length}
dem.h5   /time, /particles/{radius,body,material,position,velocity,angular_velocity},
         /clusters/{position,orientation}, /net/{position,force}, /energy/kinetic, /walls/force
coupling.h5  /steps/{time,dt,iterations,residual,converged,contact_force,in_contact,min_gap}
             /iterations/{step,iteration,residual,alpha,contact_force}, /energy/*
contact_intervals / contact_free_time: contact windows of coupled runs or of a fine-step reference
rocks / Energy / run_verdict_line / load_json: what scripts/report.py builds on (rigid bodies
with their mass from dem.json, coupling.h5 /energy, the coupler's reliability line)
"""
import json
import os

import h5py
import numpy as np


class Monitor:
    """Displacement history of the FEM monitor nodes."""

    def __init__(self, time, node_ids, displacement):
        self.time = time
        self.node_ids = list(node_ids)
        self.displacement = displacement  # steps x nodes x 3

    def node(self, node_id, component=2):
        if node_id not in self.node_ids:
            raise KeyError("node %d is not a monitor node (monitor nodes: %s)" % (node_id, self.node_ids))
        return self.displacement[:, self.node_ids.index(node_id), component]


def load_monitor(results_dir):
    path = os.path.join(results_dir, "fem.h5")
    with h5py.File(path, "r") as f:
        return Monitor(np.array(f["/monitor/time"]), np.array(f["/monitor/node_ids"]),
                       np.array(f["/monitor/displacement"]))


class Dem:
    """DEM output steps as arrays over time: time [k], position/velocity/angular_velocity
    [k, n, 3], radius/body [n]; cluster_position [k, c, 3] and cluster_orientation [k, c, 4]
    (None without clusters); net_position/net_force [j, nodes, 3] from output step
    net_first_step on (None outside coupled runs); kinetic [k] (J)."""

    def __init__(self, path):
        with h5py.File(path, "r") as f:
            def get(name):
                return np.array(f[name]) if name in f else None
            self.time = np.array(f["/time"])
            self.radius = get("/particles/radius")
            self.body = get("/particles/body")
            self.position = get("/particles/position")
            self.velocity = get("/particles/velocity")
            self.angular_velocity = get("/particles/angular_velocity")
            self.cluster_position = get("/clusters/position")
            self.cluster_orientation = get("/clusters/orientation")
            self.net_position = get("/net/position")
            self.net_force = get("/net/force")
            self.net_first_step = int(f["/net"].attrs["first_output_step"]) if "/net" in f else None
            self.kinetic = get("/energy/kinetic")
            self.material = get("/particles/material")
            self.walls_force = get("/walls/force")
            self.net_edges = get("/net/edges")


def load_dem(results_dir):
    return Dem(os.path.join(results_dir, "dem.h5"))


class Fem:
    """FEM output steps: time, load_factor [k], axial_force/strain [k, m], reaction
    [k, supports, 3] at support_nodes, displacement [k, n, 3]; max_u (m), max_time, max_node.
    Over every step, per element set (None when fem.h5 has no /element_sets): set_peak_force
    (N), set_peak_element, set_peak_time (s), set_breaking_load (N, 0: none given),
    set_exceeded (elements above it), set_first_exceedance (s, -1: never); overload: the FEM's
    warnings about them ("" when none)."""

    def __init__(self, path):
        with h5py.File(path, "r") as f:
            self.time = np.array(f["/output/time"])
            self.load_factor = np.array(f["/output/load_factor"])
            self.axial_force = np.array(f["/output/axial_force"])
            self.strain = np.array(f["/output/strain"])
            self.reaction = np.array(f["/output/reaction"])
            self.support_nodes = np.array(f["/mesh/support_nodes"])
            self.displacement = np.array(f["/output/displacement"])
            a = f["/output/displacement"].attrs
            self.max_u = float(a.get("max_magnitude", np.nan))
            self.max_time = float(a.get("max_time", np.nan))
            self.max_node = int(a.get("max_node", -1))
            self.coordinates = np.array(f["/mesh/coordinates"]) if "/mesh/coordinates" in f else None
            self.elements = np.array(f["/mesh/elements"]) if "/mesh/elements" in f else None
            self.reference_length = (np.array(f["/mesh/reference_length"])
                                     if "/mesh/reference_length" in f else None)
            self.element_set = np.array(f["/mesh/element_set"]) if "/mesh/element_set" in f else None
            self.position = np.array(f["/output/position"]) if "/output/position" in f else None
            sets = f["/element_sets"] if "/element_sets" in f else None
            def per_set(name):
                return np.array(sets[name]) if sets is not None and name in sets else None
            self.set_peak_force = per_set("peak_axial_force")
            self.set_peak_element = per_set("peak_element")
            self.set_peak_time = per_set("peak_time")
            self.set_breaking_load = per_set("breaking_load")
            self.set_exceeded = per_set("exceeded_elements")
            self.set_first_exceedance = per_set("first_exceedance_time")
            text = f.attrs.get("overload", b"")
            self.overload = text.decode() if isinstance(text, bytes) else str(text)


def load_fem(results_dir):
    return Fem(os.path.join(results_dir, "fem.h5"))


def units(path, dataset):
    """The "units" attribute of a dataset as a str."""
    with h5py.File(path, "r") as f:
        u = f[dataset].attrs["units"]
        return u.decode() if isinstance(u, bytes) else str(u)


class Coupling:
    """Per-step and per-iteration history of a coupled run."""

    def __init__(self, path):
        with h5py.File(path, "r") as f:
            steps = f["/steps"]
            self.time = np.array(steps["time"])
            self.dt = np.array(steps["dt"])
            self.iterations = np.array(steps["iterations"])
            self.residual = np.array(steps["residual"])
            self.converged = np.array(steps["converged"])
            self.contact_force = np.array(steps["contact_force"])
            self.in_contact = np.array(steps["in_contact"])
            self.min_gap = np.array(steps["min_gap"]) if "min_gap" in steps else None
            it = f["/iterations"]
            self.it_step = np.array(it["step"])
            self.it_iteration = np.array(it["iteration"])
            self.it_residual = np.array(it["residual"])
            self.it_alpha = np.array(it["alpha"])
            self.it_contact_force = np.array(it["contact_force"])

    @property
    def end_time(self):
        """/steps/time is the END time of each step (coupler/README.md)."""
        return self.time

    @property
    def start_time(self):
        return self.time - self.dt

    def force_magnitude(self):
        return np.linalg.norm(self.contact_force, axis=1)

    def total_iterations(self):
        return int(self.iterations.sum())

    def iterations_of_step(self, step):
        mask = self.it_step == step
        return self.it_iteration[mask], np.linalg.norm(self.it_contact_force[mask], axis=1)


def load_coupling(results_dir):
    return Coupling(os.path.join(results_dir, "coupling.h5"))


def contact_lost_and_regained(coupling, threshold=1e-9):
    """True if the contact force drops to zero after a first contact and returns later."""
    force = coupling.force_magnitude()
    touching = force > threshold
    if not touching.any():
        return False
    first = int(np.argmax(touching))
    after = touching[first:]
    # a gap: some False after the first True, followed by True again
    gaps = np.where(~after)[0]
    return bool(len(gaps) and after[gaps[0]:].any())


def contact_intervals(start, end, force, threshold=1e-9):
    """Time spans [t0, t1] with a contact force above threshold.

    start, end: per-sample start and end times (coupling steps: start_time, end_time; the force is
    the step average, so a contact step covers its whole step); force: magnitudes.
    Consecutive contact samples merge into one interval."""
    on = np.asarray(force) > threshold
    intervals = []
    k = 0
    n = len(on)
    while k < n:
        if on[k]:
            j = k
            while j + 1 < n and on[j + 1]:
                j += 1
            intervals.append((float(start[k]), float(end[j])))
            k = j + 1
        else:
            k += 1
    return intervals


def contact_free_time(intervals, t0, t1):
    """Seconds of [t0, t1] not covered by any of the contact intervals."""
    covered = 0.0
    for a, b in intervals:
        covered += max(0.0, min(b, t1) - max(a, t0))
    return max(0.0, (t1 - t0) - covered)


def reference_contact(npz_path, until):
    """Contact statistics of a reference_explicit.py --save file up to `until` seconds:
    dict(intervals, main (its longest window), length, fmax, peak (lowest Point A))."""
    ref = np.load(npz_path)
    m = ref["t"] <= until
    dt = ref["t"][1] - ref["t"][0]
    iv = contact_intervals(ref["t"][m], ref["t"][m] + dt, np.abs(ref["fz"][m]))
    main = max(iv, key=lambda w: w[1] - w[0])
    return dict(intervals=iv, main=main, length=main[1] - main[0],
                fmax=float(np.abs(ref["fz"][m]).max()), peak=float(ref["uA"].min()))


def run_contact(results_dir, until, window):
    """Contact statistics of a coupled run up to `until` against a reference window [t0, t1]:
    dict(n windows, free (contact-free seconds inside window), longest window, fmax, peak of
    Point A (monitor node 1), lost (contact_lost_and_regained))."""
    c = load_coupling(results_dir)
    k = c.end_time <= until
    f = c.force_magnitude()[k]
    iv = contact_intervals(c.start_time[k], c.end_time[k], f)
    return dict(n=len(iv), free=contact_free_time(iv, *window), longest=max((b - a for a, b in iv), default=0.0),
                fmax=float(f.max()), peak=float(load_monitor(results_dir).node(1).min()),
                lost=contact_lost_and_regained(c))


def load_json(path):
    """A JSON input file as a dict (ValueError naming the file when it does not parse)."""
    with open(path) as fh:
        try:
            return json.load(fh)
        except ValueError as e:
            raise ValueError("%s: not valid JSON: %s" % (path, e))


class Rock:
    """One rigid body of the DEM (a sphere or a cluster) over the output steps: particles (indices
    into /particles), mass (kg, the spheres' volumes times their density, as the DEM sums them),
    position/velocity [k, 3] of the centre of mass (mass-weighted means of the spheres: exact
    for a rigid body), kinetic [k] (J, translation + rotation: the sum over the spheres of
    1/2 m v^2 + 1/5 m r^2 |w|^2, which is the rigid body's energy by the parallel-axis rule)."""

    def __init__(self, body, particles, mass, position, velocity, kinetic):
        self.body = body
        self.particles = particles
        self.mass = mass
        self.position = position
        self.velocity = velocity
        self.kinetic = kinetic


def rocks(dem, densities):
    """The bodies of a Dem, each a Rock. densities: kg/m3 per material index (dem.json
    "materials" in order); None when unknown: masses are then NaN and the centre is the
    volume-weighted mean (exact for one material)."""
    n = len(dem.radius)
    body = dem.body if dem.body is not None else np.arange(n)
    volume = 4.0 / 3.0 * np.pi * dem.radius ** 3
    if densities is not None and dem.material is not None:
        m = volume * np.asarray(densities, dtype=float)[dem.material]
    else:
        m = volume * np.nan
    weight = m if np.all(np.isfinite(m)) else volume
    out = []
    for b in np.unique(body):
        idx = np.where(body == b)[0]
        w = weight[idx] / weight[idx].sum()
        pos = np.einsum("i,kij->kj", w, dem.position[:, idx, :])
        vel = np.einsum("i,kij->kj", w, dem.velocity[:, idx, :])
        v2 = np.sum(dem.velocity[:, idx, :] ** 2, axis=2)
        if dem.angular_velocity is not None:
            w2 = np.sum(dem.angular_velocity[:, idx, :] ** 2, axis=2)
        else:
            w2 = np.zeros_like(v2)
        ke = (0.5 * m[idx] * v2 + 0.2 * m[idx] * dem.radius[idx] ** 2 * w2).sum(axis=1)
        out.append(Rock(int(b), idx, float(m[idx].sum()), pos, vel, ke))
    return out


class Energy:
    """coupling.h5 /energy per coupling step (J): fem_/dem_ kinetic, elastic, potential (end of
    step), fem_/dem_ dissipated and external_work (in the step), created, input, limit,
    closure (accumulated); None for a dataset that is absent. attrs: the file's root attributes."""

    NAMES = ("fem_kinetic", "fem_elastic", "fem_potential", "dem_kinetic", "dem_elastic",
             "dem_potential", "fem_dissipated", "dem_dissipated", "external_work",
             "fem_interface_work", "dem_interface_work", "interface_created",
             "created", "input", "limit", "closure")

    def __init__(self, path):
        with h5py.File(path, "r") as f:
            self.time = np.array(f["/steps/time"])
            for name in self.NAMES:
                key = "/energy/" + name
                setattr(self, name, np.array(f[key]) if key in f else None)
            self.attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}


def load_energy(results_dir):
    return Energy(os.path.join(results_dir, "coupling.h5"))


def run_verdict_line(results_dir):
    """The coupler's last "results are reliable / NOT reliable" line from coupler.log (without
    the "coupler: " prefix), or None when the log or the line is missing."""
    path = os.path.join(results_dir, "coupler.log")
    if not os.path.exists(path):
        return None
    found = None
    with open(path, errors="replace") as fh:
        for line in fh:
            line = line.strip()
            if "results are reliable" in line or "results are NOT reliable" in line:
                found = line[len("coupler: "):] if line.startswith("coupler: ") else line
    return found
