"""test_make_ead_block — scripts/make_ead_block.py: mass properties of a cube and of an offset
box against their closed forms (exact), the block's volume against L^3 (1 - 6c^2 + 6c^3) and
its inertia against an independent slab integration of its octagonal cross-sections, the
proportions of the block, m = 2 E / v^2, the spheres inside the polyhedron, the STL, and the
generated dem.json run by dem_solver: the block falls as a rigid body of the given mass (the
start-up summary's mass, free fall at g, and the floor force at rest equal to m g, not the
spheres' sum)."""
import importlib.util
import json
import math
import os
import subprocess

import h5py
import numpy as np

root = os.environ["NC_ROOT"]
tmp = os.environ["NC_TMP"]
exe = os.path.join(os.environ["NC_BIN"], "dem_solver")
script = os.path.join(root, "scripts", "make_ead_block.py")
spec = importlib.util.spec_from_file_location("make_ead_block", script)
mb = importlib.util.module_from_spec(spec)
spec.loader.exec_module(mb)
failures = []


def check(cond, what):
    print(("ok  " if cond else "FAIL") + ": " + what)
    if not cond:
        failures.append(what)


def rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


# 1. cube and box: exact closed forms
rho = 2500.0
v, f, _ = mb.polyhedron(*mb.box_planes(2.0, 2.0, 2.0))
vol, m, com, inertia = mb.mass_properties(mb.triangles(v, f), rho)
check(len(v) == 8 and len(f) == 6, "cube: 8 vertices, 6 faces")
check(rel(vol, 8.0) < 1e-13 and rel(m, 8.0 * rho) < 1e-13, "cube volume a^3 = 8 (%r)" % vol)
check(np.abs(com).max() < 1e-14, "cube centre at the origin")
check(np.abs(inertia - m * 4.0 / 6.0 * np.eye(3)).max() < 1e-12 * m, "cube inertia m a^2 / 6")

a, b, c, ctr = 0.7, 1.3, 2.1, (3.0, -1.5, 0.25)
v, f, _ = mb.polyhedron(*mb.box_planes(a, b, c, ctr))
vol, m, com, inertia = mb.mass_properties(mb.triangles(v, f), rho)
ref = m / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
check(rel(vol, a * b * c) < 1e-13, "box volume a b c (%r vs %r)" % (vol, a * b * c))
check(np.abs(com - ctr).max() < 1e-13, "box centre of mass at its centre, off the origin: %s" % com)
check(np.abs(inertia - ref).max() < 1e-12 * ref.max(), "box inertia m (b^2 + c^2) / 12 ... about its centre")


# 2. the block: proportions, volume, inertia
def slab_inertia(L, cc, density):
    """Independent: I_zz and I_xx of the block from its cross-sections z = const, octagons
    |x|, |y| <= m(z) = min(L/2, k - |z|) with |x| + |y| <= k, k = L (1 - c); polygon area and
    second moments by the shoelace formulas, integrated over z with 5-point Gauss-Legendre on
    each piece where the vertices are linear in z (exact for the polynomial integrand)."""
    h, k = L / 2, L * (1 - cc)

    def section(z):
        mz = min(h, k - abs(z))
        if 2 * mz > k:
            e = k - mz
            pts = [(mz, -e), (mz, e), (e, mz), (-e, mz), (-mz, e), (-mz, -e), (-e, -mz), (e, -mz)]
        else:
            pts = [(mz, -mz), (mz, mz), (-mz, mz), (-mz, -mz)]
        A = Ixx2 = Iyy2 = 0.0
        for (x0, y0), (x1, y1) in zip(pts, pts[1:] + pts[:1]):
            cr = x0 * y1 - x1 * y0
            A += cr / 2
            Iyy2 += cr * (x0 * x0 + x0 * x1 + x1 * x1) / 12   # ∫ x^2 dA
            Ixx2 += cr * (y0 * y0 + y0 * y1 + y1 * y1) / 12   # ∫ y^2 dA
        return A, Iyy2, Ixx2

    xg, wg = np.polynomial.legendre.leggauss(5)
    V = Izz = Ixx = 0.0
    cuts = [0.0, k - h, k / 2, h]
    for lo, hi in zip(cuts, cuts[1:]):
        for x, w in zip(xg, wg):
            z = 0.5 * (lo + hi) + 0.5 * (hi - lo) * x
            A, x2, y2 = section(z)
            ww = w * 0.5 * (hi - lo) * 2  # both signs of z
            V += ww * A
            Izz += ww * (x2 + y2)
            Ixx += ww * (y2 + z * z * A)
    return V, density * Izz, density * Ixx


for cc in (1.0 / 3.0, 0.2):
    L = 1.3
    v, f, planes = mb.polyhedron(*mb.block_planes(L, cc))
    tris = mb.triangles(v, f)
    vol, m, com, inertia = mb.mass_properties(tris, rho)
    sizes = sorted(len(x) for x in f)
    check(len(f) == 18 and sizes == [4] * 6 + [6] * 12 and len(v) == 32,
          "c = %.3f: 6 squares + 12 hexagons, 32 vertices" % cc)
    check(np.allclose(v.max(axis=0) - v.min(axis=0), L, rtol=1e-13), "bounding box L x L x L")
    sq = [x for x in f if len(x) == 4][0]
    side = np.linalg.norm(v[sq[0]] - v[sq[1]])
    check(rel(side, L * (1 - 2 * cc)) < 1e-12, "square faces of side L (1 - 2c) = %.4f" % side)
    # every axis view: the square L with its corners cut by c L on both sides
    xy = v[:, :2]
    check(np.all(np.abs(xy).sum(axis=1) <= L * (1 - cc) + 1e-12) and
          np.any(np.isclose(np.abs(xy).sum(axis=1), L * (1 - cc))), "views: corners cut at c L")
    check(rel(vol, L ** 3 * mb.volume_factor(cc)) < 1e-12,
          "volume L^3 (1 - 6c^2 + 6c^3) = %.6f (got %.6f)" % (L ** 3 * mb.volume_factor(cc), vol))
    Vs, Izz, Ixx = slab_inertia(L, cc, rho)
    check(rel(Vs, vol) < 1e-12, "slab volume agrees (%.12g vs %.12g)" % (Vs, vol))
    check(rel(inertia[2, 2], Izz) < 1e-11 and rel(inertia[0, 0], Ixx) < 1e-11,
          "inertia vs slab integration: %.10g / %.10g, %.10g / %.10g" % (inertia[2, 2], Izz, inertia[0, 0], Ixx))
    check(np.abs(inertia - inertia[0, 0] * np.eye(3)).max() < 1e-12 * inertia[0, 0],
          "cubic symmetry: isotropic inertia, no products")
    check(np.abs(com).max() < 1e-13 * L, "centre of mass at the centre")
check(abs(mb.volume_factor(1.0 / 3.0) - 5.0 / 9.0) < 1e-15, "c = 1/3: V = 5/9 L^3")

# 3. mass from energy and speed; the written cluster
out = os.path.join(tmp, "block.json")
stl = os.path.join(tmp, "block.stl")
r = subprocess.run(["/usr/bin/python3", script, "--energy-kj", "1000", "--speed", "25",
                    "--output", out, "--stl", stl, "--position", "1", "2", "3"],
                   capture_output=True, text=True)
check(r.returncode == 0, "script exits 0: " + r.stderr)
doc = json.load(open(out))
cl = doc["clusters"][0]
check(rel(cl["mass_kg"], 2 * 1000e3 / 25 ** 2) < 1e-12, "m = 2 E / v^2 = 3200 kg (%r)" % cl["mass_kg"])
check(rel(math.sqrt(sum(x * x for x in cl["velocity"])), 25.0) < 1e-12 and cl["velocity"][2] < 0,
      "velocity 25 m/s along -z")
check(np.allclose(cl["center_of_mass"], [1, 2, 3]), "centre of mass at --position")
check(doc["materials"][0]["density_kg_m3"] == mb.DENSITY_KG_M3, "default density written")
L = (3200 / mb.DENSITY_KG_M3 / mb.volume_factor(1 / 3)) ** (1 / 3)
n, d = mb.block_planes(L, 1 / 3)
n = np.array(n)
c = np.array([s["position"] for s in cl["spheres"]]) - np.array([1, 2, 3])
rad = cl["spheres"][0]["radius"]
gap = (np.array(d)[None, :] - c @ n.T).min(axis=1)
check(gap.min() >= rad - 1e-9 and abs(gap.min() - rad) < 1e-9,
      "spheres inside the polyhedron and touching its faces (min gap %.6g, r %.6g)" % (gap.min(), rad))
with open(stl) as fh:
    text = fh.read()
check(text.startswith("solid") and text.count("facet normal") == 6 * 2 + 12 * 4,
      "STL with the 60 triangles of the polyhedron")
r = subprocess.run(["/usr/bin/python3", script, "--mass-kg", "800", "--energy-kj", "100", "--speed", "25",
                    "--output", out], capture_output=True, text=True)
check(r.returncode == 2 and "at most one" in r.stderr, "over-determined size refused: " + r.stderr.strip())
r = subprocess.run(["/usr/bin/python3", script, "--mass-kg", "-1", "--output", out],
                   capture_output=True, text=True)
check(r.returncode == 2 and "--mass-kg" in r.stderr, "negative mass refused: " + r.stderr.strip())

# 4. dem_solver runs it: a drop onto a floor, the body falling and resting with its true mass
frag = os.path.join(tmp, "frag.json")
r = subprocess.run(["/usr/bin/python3", script, "--mass-kg", "800", "--speed", "1", "--sphere-radius", "0.2",
                    "--spacing", "0.8", "--restitution", "0.2", "--output", frag],
                   capture_output=True, text=True)
check(r.returncode == 0, "small block written: " + r.stderr)
doc = json.load(open(frag))
cl = doc["clusters"][0]
low = min(s["position"][2] - s["radius"] for s in cl["spheres"])
doc["planes"] = [{"point": [0, 0, low - 0.05], "normal": [0, 0, 1]}]
doc.update({"end_time_s": 0.6, "output_interval_s": 0.01, "dt_s": 1e-5})
case = os.path.join(tmp, "drop.json")
json.dump(doc, open(case, "w"))
res = os.path.join(tmp, "drop")
r = subprocess.run([exe, case, "--output", res], capture_output=True, text=True, timeout=600)
check(r.returncode == 0, "dem_solver accepts the generated dem.json: " + r.stderr[-500:])
rho_s = doc["materials"][0]["density_kg_m3"]
m_spheres = sum(4 / 3 * math.pi * s["radius"] ** 3 * rho_s for s in cl["spheres"])
check("total mass 800 kg" in r.stdout, "summary shows the true 800 kg (spheres' sum %.0f kg): %s"
      % (m_spheres, r.stdout.splitlines()[0] if r.stdout else ""))
with h5py.File(os.path.join(res, "dem.h5"), "r") as f:
    t = f["time"][:]
    z = f["clusters/position"][:, 0, 2]
    fz = f["walls/force"][:, 0, 2]
# before touching (0.05 m at 1 m/s, t > 0.04 s): z = z0 - t - g t^2 / 2
check(abs(z[1] - (z[0] - t[1] - 0.5 * 9.81 * t[1] ** 2)) < 1e-6, "free fall of the centre of mass")
# at rest on the floor: the force on the floor is the weight of the GIVEN mass
w = 800 * 9.81
check(rel(-fz[-1], w) < 1e-3,  # force ON the floor points down
      "floor force at rest %.1f N = m g %.1f N (spheres' sum would give %.1f N)" % (fz[-1], w, m_spheres * 9.81))
check(abs(m_spheres - 800) > 0.1 * 800, "the spheres' sum differs from the true mass (the test can tell)")

if failures:
    print("%d check(s) failed" % len(failures))
    raise SystemExit(1)
print("all checks passed")
