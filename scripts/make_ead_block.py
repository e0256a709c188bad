#!/usr/bin/python3
"""make_ead_block — the polyhedral test block of a rockfall barrier certification test
(EAD 340059-00-0106, formerly ETAG 027) as a dem_solver cluster with its true mass properties.

The block is a cube of edge L whose 12 edges are cut at 45 degrees, each cut removing a leg
of c*L from both faces it joins (c = --chamfer, default 1/3): every axis view is the square L x L
with its corners cut at L/3, i.e. 6 square faces of side L(1 - 2c) and 12 hexagonal faces,
volume L^3 (1 - 6 c^2 + 6 c^3) (5/9 L^3 for c = 1/3). dem_solver/README.md ("Certification
block") says what the standard prescribes and which choices are made here.

From a mass (--mass-kg) or an energy and a speed (--energy-kj, --speed: m = 2 E / v^2) and the
density, the script computes L, then from the polyhedron itself (its triangulated surface, signed
tetrahedra from the origin, i.e. the divergence theorem) the exact volume, mass, centre of mass
and inertia tensor, and writes them into the cluster (`mass_kg`, `center_of_mass`,
`inertia_kg_m2`) with a filling of overlapping spheres: a shell of spheres of radius r centred
on the polyhedron shrunk by r (so the spheres touch every face plane and round edges and
corners by r) on a square grid of spacing s, plus a lattice filling the inside. The report
printed (and `description`) gives the approximation: the volume of the rounded envelope
(Steiner's formula) against the polyhedron's, the depth of the dimples between shell spheres,
r - sqrt(r^2 - s^2/2), and the sphere count. Also writes the polyhedron as an ASCII STL.

    scripts/make_ead_block.py --energy-kj 1000 --speed 25 --output block.json --stl block.stl
    scripts/make_ead_block.py --mass-kg 3200 --speed 25 --fragment --output block_cluster.json
"""
import argparse
import json
import math
import sys

import numpy as np

# Defaults, documented in dem_solver/README.md ("Certification block")
DENSITY_KG_M3 = 2600.0      # concrete block
CHAMFER = 1.0 / 3.0         # cut leg as a fraction of the edge L
SPHERE_RADIUS = 1.0 / 8.0   # shell sphere radius as a fraction of L
SPACING = 0.6               # shell grid spacing as a fraction of the sphere radius
MIN_SPEED_M_S = 25.0        # the MEL test's minimum impact speed


# ---- convex polyhedra from half-spaces n . x <= d ----------------------------------------------

def polyhedron(normals, offsets, tol=1e-12):
    """Vertices and faces (vertex indices counter-clockwise seen from outside, one list per
    half-space that bounds a face) of the convex polyhedron {x : n_i . x <= d_i}."""
    n = np.asarray(normals, float)
    d = np.asarray(offsets, float)
    scale = max(1.0, np.abs(d).max())
    verts = []
    m = len(n)
    for i in range(m):
        for j in range(i + 1, m):
            for k in range(j + 1, m):
                a = np.array([n[i], n[j], n[k]])
                if abs(np.linalg.det(a)) < 1e-12:
                    continue
                x = np.linalg.solve(a, [d[i], d[j], d[k]])
                if np.all(n @ x <= d + tol * scale) and \
                        not any(np.linalg.norm(x - v) < 1e-9 * scale for v in verts):
                    verts.append(x)
    verts = np.array(verts)
    faces, face_planes = [], []
    for i in range(m):
        on = [q for q in range(len(verts)) if abs(n[i] @ verts[q] - d[i]) < 1e-9 * scale]
        if len(on) < 3:
            continue
        c = verts[on].mean(axis=0)
        u = verts[on[0]] - c
        u /= np.linalg.norm(u)
        w = np.cross(n[i], u)
        ang = [math.atan2((verts[q] - c) @ w, (verts[q] - c) @ u) for q in on]
        faces.append([q for _, q in sorted(zip(ang, on))])
        face_planes.append(i)
    return verts, faces, face_planes


def triangles(verts, faces):
    """Fan triangulation of the convex faces: array [t, 3, 3]."""
    tris = []
    for f in faces:
        for k in range(1, len(f) - 1):
            tris.append([verts[f[0]], verts[f[k]], verts[f[k + 1]]])
    return np.array(tris)


def mass_properties(tris, density):
    """Volume, mass, centre of mass and inertia tensor about it of the closed, outward oriented
    triangulated surface `tris`: each triangle and the origin make a signed tetrahedron with
    volume det/6, first moment det/24 (a + b + c), second moment
    det/120 (a a^T + b b^T + c c^T + s s^T), s = a + b + c (exact for a polynomial density of
    degree 0 over a tetrahedron); the sums are the integrals over the solid."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    vol = det.sum() / 6.0
    first = (det[:, None] * (a + b + c)).sum(axis=0) / 24.0
    s = a + b + c
    outer = lambda p: p[:, :, None] * p[:, None, :]  # noqa: E731
    second = (det[:, None, None] * (outer(a) + outer(b) + outer(c) + outer(s))).sum(axis=0) / 120.0
    com = first / vol
    cov = second - vol * np.outer(com, com)          # ∫ (x - com)(x - com)^T dV
    inertia = density * (np.trace(cov) * np.eye(3) - cov)
    return vol, density * vol, com, inertia


def box_planes(lx, ly, lz, centre=(0.0, 0.0, 0.0)):
    normals, offsets = [], []
    for axis, half in enumerate((lx / 2, ly / 2, lz / 2)):
        for sign in (1.0, -1.0):
            nrm = [0.0, 0.0, 0.0]
            nrm[axis] = sign
            normals.append(nrm)
            offsets.append(half + sign * centre[axis])
    return normals, offsets


def block_planes(edge, chamfer):
    """The block centred at the origin: |x|, |y|, |z| <= L/2 and |x_i| + |x_j| <= L (1 - c)."""
    normals, offsets = box_planes(edge, edge, edge)
    k = edge * (1.0 - chamfer)
    for i, j in ((0, 1), (0, 2), (1, 2)):
        for si in (1.0, -1.0):
            for sj in (1.0, -1.0):
                nrm = [0.0, 0.0, 0.0]
                nrm[i], nrm[j] = si / math.sqrt(2.0), sj / math.sqrt(2.0)
                normals.append(nrm)
                offsets.append(k / math.sqrt(2.0))
    return normals, offsets


def volume_factor(chamfer):
    """V / L^3 of the block (inclusion-exclusion of the 12 edge cuts, see the module text)."""
    return 1.0 - 6.0 * chamfer ** 2 + 6.0 * chamfer ** 3


# ---- the sphere filling -----------------------------------------------------------------------

def sphere_filling(normals, offsets, radius, spacing):
    """Centres of spheres of `radius`: a shell on the faces of the polyhedron shrunk by radius
    (grid of `spacing` on each face, its edges and vertices included) and a cubic lattice inside
    it whose spheres cover it (spacing <= 2 r / sqrt 3). Returns centres and the shrunk
    polyhedron (vertices, faces)."""
    n = np.asarray(normals, float)
    inner_d = np.asarray(offsets, float) - radius
    verts, faces, planes = polyhedron(n, inner_d)
    pts = [v for v in verts]
    for f, i in zip(faces, planes):
        poly = verts[f]
        # edges of the face
        for a, b in zip(poly, np.roll(poly, -1, axis=0)):
            cnt = max(1, int(math.ceil(np.linalg.norm(b - a) / spacing)))
            for t in range(1, cnt):
                pts.append(a + (b - a) * t / cnt)
        # interior grid in the face plane, kept where inside the face
        c = poly.mean(axis=0)
        u = poly[0] - c
        u /= np.linalg.norm(u)
        w = np.cross(n[i], u)
        pu, pw = (poly - c) @ u, (poly - c) @ w
        for gu in np.arange(pu.min() + spacing / 2, pu.max(), spacing):
            for gw in np.arange(pw.min() + spacing / 2, pw.max(), spacing):
                p = c + gu * u + gw * w
                gap = inner_d - n @ p
                gap[i] = spacing  # on its own face plane
                if np.all(gap >= 0.5 * spacing):
                    pts.append(p)
    lattice = 2.0 * radius / math.sqrt(3.0) * 0.99
    lo, hi = verts.min(axis=0), verts.max(axis=0)
    axes = [np.arange(lo[k] + lattice / 2, hi[k], lattice) for k in range(3)]
    for x in axes[0]:
        for y in axes[1]:
            for z in axes[2]:
                p = np.array([x, y, z])
                if np.all(n @ p <= inner_d - 0.5 * spacing):
                    pts.append(p)
    out = []
    for p in pts:  # merge the shared edge and vertex points of neighbouring faces
        if not any(np.linalg.norm(p - q) < 0.25 * spacing for q in out):
            out.append(p)
    return np.array(out), verts, faces


def steiner_volume(verts, faces, normals_of_faces, radius):
    """Volume of the convex polyhedron grown by `radius` (the envelope of the shell spheres):
    V + A r + (1/2) sum_edges l_e theta_e r^2 + 4/3 pi r^3, theta_e the angle between the
    normals of the two faces of edge e."""
    tris = triangles(verts, faces)
    vol = mass_properties(tris, 1.0)[0]
    area = 0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1).sum()
    edge_faces = {}
    for fi, f in enumerate(faces):
        for a, b in zip(f, f[1:] + f[:1]):
            edge_faces.setdefault(tuple(sorted((a, b))), []).append(fi)
    mean_term = 0.0
    for (a, b), fs in edge_faces.items():
        n1, n2 = normals_of_faces[fs[0]], normals_of_faces[fs[1]]
        theta = math.acos(max(-1.0, min(1.0, float(np.dot(n1, n2)))))
        mean_term += np.linalg.norm(verts[a] - verts[b]) * theta
    return vol + area * radius + 0.5 * mean_term * radius ** 2 + 4.0 / 3.0 * math.pi * radius ** 3


# ---- outputs ----------------------------------------------------------------------------------

def write_stl(path, tris, name="ead_block"):
    with open(path, "w") as f:
        f.write("solid %s\n" % name)
        for t in tris:
            nrm = np.cross(t[1] - t[0], t[2] - t[0])
            nrm /= np.linalg.norm(nrm)
            f.write(" facet normal %.9g %.9g %.9g\n  outer loop\n" % tuple(nrm))
            for v in t:
                f.write("   vertex %.12g %.12g %.12g\n" % tuple(v))
            f.write("  endloop\n endfacet\n")
        f.write("endsolid %s\n" % name)


def build(mass_kg, density, chamfer, radius_fraction, spacing_fraction, position):
    """Everything about the block: geometry, mass properties, spheres, approximation figures."""
    edge = (mass_kg / density / volume_factor(chamfer)) ** (1.0 / 3.0)
    normals, offsets = block_planes(edge, chamfer)
    verts, faces, planes = polyhedron(normals, offsets)
    tris = triangles(verts, faces)
    vol, mass, com, inertia = mass_properties(tris, density)
    r = radius_fraction * edge
    s = spacing_fraction * r
    centres, in_verts, in_faces = sphere_filling(normals, offsets, r, s)
    in_normals = [np.asarray(normals[i]) for i in polyhedron(normals, np.asarray(offsets) - r)[2]]
    envelope = steiner_volume(in_verts, in_faces, in_normals, r)
    shift = np.asarray(position, float) - com
    return {
        "edge_m": edge, "chamfer": chamfer, "volume_m3": vol, "mass_kg": mass,
        "center_of_mass": com + shift, "inertia_kg_m2": inertia,
        "triangles": tris + shift, "vertices": verts + shift, "faces": faces,
        "sphere_radius_m": r, "spacing_m": s, "centres": centres + shift,
        "envelope_volume_m3": envelope, "dimple_m": r - math.sqrt(max(0.0, r * r - s * s / 2.0)),
    }


def cluster_json(blk, velocity, material):
    return {
        "material": material,
        "spheres": [{"position": [round(float(x), 12) for x in c], "radius": blk["sphere_radius_m"]}
                    for c in blk["centres"]],
        "mass_kg": blk["mass_kg"],
        "center_of_mass": [float(x) for x in blk["center_of_mass"]],
        "inertia_kg_m2": [[float(x) for x in row] for row in blk["inertia_kg_m2"]],
        "velocity": [float(x) for x in velocity],
    }


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    g = p.add_argument_group("size (give --mass-kg, or --energy-kj and --speed)")
    g.add_argument("--mass-kg", type=float, help="block mass (kg)")
    g.add_argument("--energy-kj", type=float, help="impact energy (kJ); with --speed gives m = 2 E / v^2")
    g.add_argument("--speed", type=float, help="impact speed (m/s); default with --mass-kg: "
                   "from --energy-kj, else %g (the MEL minimum)" % MIN_SPEED_M_S)
    p.add_argument("--density", type=float, default=DENSITY_KG_M3,
                   help="block density (kg/m^3, default %g)" % DENSITY_KG_M3)
    p.add_argument("--chamfer", type=float, default=CHAMFER,
                   help="edge cut leg / L, in (0, 0.5) (default 1/3)")
    p.add_argument("--sphere-radius", type=float, default=SPHERE_RADIUS,
                   help="sphere radius / L (default %g)" % SPHERE_RADIUS)
    p.add_argument("--spacing", type=float, default=SPACING,
                   help="shell grid spacing / sphere radius (default %g)" % SPACING)
    p.add_argument("--position", type=float, nargs=3, default=[0.0, 0.0, 0.0],
                   help="centre of mass at t = 0 (m)")
    p.add_argument("--direction", type=float, nargs=3, default=[0.0, 0.0, -1.0],
                   help="direction of the initial velocity (default -z)")
    p.add_argument("--material", default="concrete", help="material name (default concrete)")
    p.add_argument("--youngs-modulus", type=float, default=3e10, help="Pa (default 3e10)")
    p.add_argument("--poisson-ratio", type=float, default=0.2, help="default 0.2")
    p.add_argument("--restitution", type=float, default=0.3, help="default 0.3")
    p.add_argument("--friction", type=float, default=0.5, help="default 0.5")
    p.add_argument("--fragment", action="store_true",
                   help="write only {\"clusters\": [...]} to merge into a dem.json that defines the material")
    p.add_argument("--output", required=True, help="dem.json (or fragment) to write")
    p.add_argument("--stl", help="also write the polyhedron as an ASCII STL")
    a = p.parse_args(argv)

    def fail(msg):
        print("make_ead_block: " + msg, file=sys.stderr)
        return 2

    for name in ("mass_kg", "energy_kj", "speed"):
        v = getattr(a, name)
        if v is not None and not (math.isfinite(v) and v > 0):
            return fail("--%s: expected a number > 0, got %g" % (name.replace("_", "-"), v))
    if not (math.isfinite(a.density) and a.density > 0):
        return fail("--density: expected a number > 0")
    if not 0.0 < a.chamfer < 0.5:
        return fail("--chamfer: expected a value in (0, 0.5), got %g" % a.chamfer)
    if not 0.0 < a.sphere_radius < a.chamfer / 2 + 0.25 or not 0.0 < a.spacing <= 1.0:
        return fail("--sphere-radius must be in (0, 0.25 + chamfer/2) and --spacing in (0, 1]")
    if a.mass_kg is not None:
        if a.energy_kj is not None and a.speed is not None:
            return fail("give --mass-kg with at most one of --energy-kj and --speed")
        mass = a.mass_kg
        speed = math.sqrt(2e3 * a.energy_kj / mass) if a.energy_kj is not None else \
            (a.speed if a.speed is not None else MIN_SPEED_M_S)
    elif a.energy_kj is not None and a.speed is not None:
        mass = 2e3 * a.energy_kj / a.speed ** 2
        speed = a.speed
    else:
        return fail("give --mass-kg, or --energy-kj and --speed")
    dnorm = math.sqrt(sum(x * x for x in a.direction))
    if not dnorm > 0:
        return fail("--direction: expected a non-zero vector")
    velocity = [speed * x / dnorm for x in a.direction]
    if speed < MIN_SPEED_M_S:
        print("make_ead_block: note: %.4g m/s is below the %g m/s of the MEL test" % (speed, MIN_SPEED_M_S),
              file=sys.stderr)

    blk = build(mass, a.density, a.chamfer, a.sphere_radius, a.spacing, a.position)
    energy = 0.5 * blk["mass_kg"] * speed ** 2
    desc = ("EAD 340059 polyhedral block: L %.4f m, chamfer %.4g L, density %g kg/m3, mass %.6g kg, "
            "%.6g kJ at %.4g m/s; %d spheres of r %.4g m (envelope %.4f of the polyhedron's volume, "
            "dimples %.3g m)" % (blk["edge_m"], a.chamfer, a.density, blk["mass_kg"], energy / 1e3,
                                 speed, len(blk["centres"]), blk["sphere_radius_m"],
                                 blk["envelope_volume_m3"] / blk["volume_m3"], blk["dimple_m"]))
    cluster = cluster_json(blk, velocity, a.material)
    if a.fragment:
        doc = {"clusters": [cluster]}
    else:
        doc = {"description": desc,
               "materials": [{"name": a.material, "youngs_modulus_pa": a.youngs_modulus,
                              "poisson_ratio": a.poisson_ratio, "density_kg_m3": a.density,
                              "restitution": a.restitution, "friction": a.friction}],
               "clusters": [cluster]}
    with open(a.output, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
    if a.stl:
        write_stl(a.stl, blk["triangles"])
    print("make_ead_block: " + desc)
    i = blk["inertia_kg_m2"]
    print("  volume %.6g m3, centre of mass %s m, inertia diag %.6g %.6g %.6g kg m2"
          % (blk["volume_m3"], np.array2string(blk["center_of_mass"], precision=6), i[0, 0], i[1, 1], i[2, 2]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
