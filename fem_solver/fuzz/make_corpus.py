#!/usr/bin/env python3
"""Writes the seed corpora of the fem_solver fuzz targets (Gmsh 2.2/4.1 meshes, fem.json),
including the inputs that once overflowed the Gmsh reader's buffers."""
import json, os

here = os.path.dirname(os.path.abspath(__file__))
H2 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
H4 = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
N2 = "$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 2 0 0\n$EndNodes\n"
gmsh = {
    "cable22.msh": H2 + "$PhysicalNames\n2\n0 1 \"anchors\"\n1 2 \"stiff\"\n$EndPhysicalNames\n"
        "$Nodes\n4\n10 0 0 0\n20 1 0 0\n30 2 0 0\n40 3 0 0\n$EndNodes\n"
        "$Elements\n5\n1 15 2 1 1 10\n2 15 2 1 4 40\n3 1 2 0 1 10 20\n4 1 2 2 2 20 30\n5 1 2 0 3 30 40\n$EndElements\n",
    "cable41.msh": H4 + "$PhysicalNames\n2\n0 1 \"anchors\"\n1 2 \"stiff\"\n$EndPhysicalNames\n"
        "$Entities\n2 2 0 0\n1 0 0 0 1 1\n2 3 0 0 1 1\n1 0 0 0 2 0 0 0 2 1 2\n2 2 0 0 3 0 0 1 2 2 1 2\n$EndEntities\n"
        "$Nodes\n2 4 1 4\n1 1 0 2\n1\n4\n0 0 0\n3 0 0\n1 2 0 2\n2\n3\n1 0 0\n2 0 0\n$EndNodes\n"
        "$Elements\n4 5 1 5\n0 1 15 1\n1 1\n0 2 15 1\n2 4\n1 1 1 2\n3 1 2\n5 3 4\n1 2 1 1\n4 2 3\n$EndElements\n",
    "block_minus1.msh": H4 + "$Nodes\n1 2 1 2\n0 1 0 -1\n1\n2\n0 0 0\n1 0 0\n$EndNodes\n",
    "tags_minus5.msh": H2 + N2 + "$Elements\n1\n5 1 -5 3 4\n$EndElements\n",
    "nan_node.msh": H2 + "$Nodes\n1\n1 0 nan 0\n$EndNodes\n",
    "other_types.msh": H2 + N2 + "$Elements\n2\n1 2 2 0 1 1 2 3\n2 1 2 0 1 1 3\n$EndElements\n",
}
for name, text in gmsh.items():
    open(os.path.join(here, "corpus_gmsh", name), "w").write(text)

sets = [{"name": "rope", "youngs_modulus_pa": 1e11, "area_m2": 1.1e-4, "density_kg_m3": 7850}]
fem = {
    "net.json": {"net": {"origin_m": [0, 0, 5], "edge1_m": [4, 0, 0], "edge2_m": [0, 4, 0], "count1": 5, "count2": 5},
                 "element_sets": sets, "supports": [{"nodes": "boundary"}],
                 "point_loads": [{"nodes": "center", "force_n": [0, 0, -1e4]}],
                 "node_sets": {"mine": [6, 7, "corners"]}, "monitor_nodes": ["center"],
                 "analysis": {"type": "dynamic", "dt_s": 1e-3, "end_time_s": 0.1}},
    "explicit.json": {"nodes": [[0, 0, 0], [1, 0, 0], [2, 0, 0]], "elements": [[0, 1], {"nodes": [1, 2], "set": "rope"}],
                      "element_sets": sets, "supports": [{"nodes": [0, 2]}], "self_weight": True,
                      "rayleigh": {"tau_per_s": 1}, "interface": {"element_sets": ["rope"]},
                      "output": {"interval_steps": 2}, "analysis": {"type": "static", "load_steps": 2}},
    "mesh.json": {"mesh": {"file": "cable22.msh"}, "element_sets": sets, "supports": [{"nodes": "anchors"}]},
}
for name, doc in fem.items():
    open(os.path.join(here, "corpus_fem_json", name), "w").write(json.dumps(doc))
open(os.path.join(here, "corpus_fem_json", "duplicate.json"), "w").write(
    '{"nodes": [[0,0,0],[1,0,0]], "elements": [[0,1]], "element_sets": [{"name": "a", "youngs_modulus_pa": 1e11, "area_m2": 1e-4}], "analysis": {"dt_s": 1e-3, "dt_s": 1e-300}}')
open(os.path.join(here, "corpus_fem_json", "huge_number.json"), "w").write(
    '{"nodes": [[0,0,0],[1e400,0,0]], "elements": [[0,1]], "element_sets": [{"name": "a", "youngs_modulus_pa": 1e11, "area_m2": 1e-4}]}')
