#!/usr/bin/env python3
"""Writes the seed corpora of the dem_solver fuzz targets (STL files, dem.json), including
an ASCII STL with a NUL byte inside a facet (once read as 4 facets of 1360)."""
import json, math, os, struct

here = os.path.dirname(os.path.abspath(__file__))
tri = [[0, 0, 0, 1, 0, 0, 1, 1, 0], [0, 0, 0, 1, 1, 0, 0, 1, 0]]

def ascii_stl(facets):
    out = "solid s\n"
    for t in facets:
        out += "  facet normal 0 0 1\n    outer loop\n"
        for v in range(3):
            out += "      vertex %g %g %g\n" % tuple(t[3 * v:3 * v + 3])
        out += "    endloop\n  endfacet\n"
    return out + "endsolid s\n"

def binary_stl(facets, head=b"binary", announced=None):
    n = len(facets) if announced is None else announced
    data = head.ljust(80, b"\0") + struct.pack("<I", n)
    for t in facets:
        data += struct.pack("<3f", 0, 0, 1) + struct.pack("<9f", *t) + b"\0\0"
    return data

terrain = []
for i in range(4):
    for j in range(2):
        z = lambda x, y: 0.1 * math.sin(x) * math.cos(y)
        x0, y0 = 0.25 * i, 0.25 * j
        p = [(x0, y0), (x0 + 0.25, y0), (x0 + 0.25, y0 + 0.25), (x0, y0 + 0.25)]
        a, b, c, d = [(x, y, z(x, y)) for x, y in p]
        terrain += [list(a + b + c), list(a + c + d)]
text = ascii_stl(terrain)
seeds = {
    "square_ascii.stl": ascii_stl(tri).encode(),
    "square_binary.stl": binary_stl(tri),
    "solid_header_binary.stl": binary_stl(tri, b"solid exported"),
    "miscount.stl": binary_stl(tri, b"binary", 3),
    "terrain_ascii.stl": text.encode(),
    "terrain_nul.stl": (text[:500] + "\0" + text[501:]).encode(),
    "truncated.stl": text[: len(text) // 2].encode(),
    "nan.stl": binary_stl([tri[0], [0, 0, 0, 1, float("nan"), 0, 1, 1, 0]]),
}
for name, data in seeds.items():
    open(os.path.join(here, "corpus_stl", name), "wb").write(data)

rock = [{"name": "rock", "youngs_modulus_pa": 3e10, "poisson_ratio": 0.2, "density_kg_m3": 2600,
         "restitution": 0.3, "friction": 0.5}]
dem = {
    "rock_on_plane.json": {"materials": rock, "particles": [{"position": [0, 0, 1], "radius": 0.3, "velocity": [0, 0, -20]}],
                           "planes": [{"point": [0, 0, 0], "normal": [0, 0, 1]}], "dt_s": 1e-5, "end_time_s": 0.1},
    "generators.json": {"materials": rock, "generators": [
        {"type": "lattice", "min": [0, 0, 0], "max": [1, 1, 1], "radius": 0.2},
        {"type": "random", "min": [2, 0, 0], "max": [3, 1, 1], "radius": 0.1, "count": 5, "seed": 3}],
        "dt_s": "auto", "end_time_s": 0.01},
    "cluster_net.json": {"materials": rock, "clusters": [{"spheres": [{"position": [0, 0, 1], "radius": 0.2},
                                                                   {"position": [0.2, 0, 1], "radius": 0.2}]}],
                         "net_wall": {"youngs_modulus_pa": 1e11, "poisson_ratio": 0.3, "friction": 0.3},
                         "contact_law": "hertz", "threads": 1},
    "mesh.json": {"materials": rock, "meshes": [{"file": "square_ascii.stl"}], "dt_s": 1e-5},
}
for name, doc in dem.items():
    open(os.path.join(here, "corpus_dem_json", name), "w").write(json.dumps(doc))
open(os.path.join(here, "corpus_dem_json", "tiny_dt.json"), "w").write(
    json.dumps({"materials": rock, "particles": [{"position": [0, 0, 1], "radius": 0.3}], "dt_s": 1e-300, "end_time_s": 1}))
open(os.path.join(here, "corpus_dem_json", "duplicate.json"), "w").write(
    '{"materials": [{"name": "rock", "youngs_modulus_pa": 3e10, "poisson_ratio": 0.2, "density_kg_m3": 2600, "restitution": 0.3, "friction": 0.5, "friction": 0.9}]}')
