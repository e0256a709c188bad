"""test_make_barrier — scripts/make_barrier.py: the barrier's topology (node and element counts
per type from the grid by hand, node sets), the masses of every set against rho A L computed
here from the parameters, each support rope one sliding chain from brake to brake through
every shackle node of its edge with its brakes at anchors, every post hinged (base pinned,
top free and held by ropes), and fem_solver on the result: it reads it, its start-up summary
gives the same masses, and the barrier's equilibrium under self-weight and prestress: a
dynamic run starts at rest in it (make_barrier's default initial state) and stays there, and
a static analysis reaches it too, both with support reactions that balance the weight
(1e-8 relative). A taut-only net with slack meshes (the top rope sags more than the net's
pretension stretches its meshes) has dofs that nothing holds in Newton's first iterates,
which fem_solver's static Newton finds singular; fem_solver then solves the load step by
pseudo-time steps, whose mass term keeps the matrix regular, and the test checks it says so.
Also the ring-net variant: read and run a few dynamic steps."""
import json
import math
import os
import subprocess

import h5py
import numpy as np

root = os.environ["NC_ROOT"]
tmp = os.environ["NC_TMP"]
exe = os.path.join(os.environ["NC_BIN"], "fem_solver")
script = os.path.join(root, "scripts", "make_barrier.py")
failures = []


def check(cond, what):
    print(("ok  " if cond else "FAIL") + ": " + what)
    if not cond:
        failures.append(what)


def make(name, *args):
    path = os.path.join(tmp, name + ".json")
    out = subprocess.run(["/usr/bin/python3", script, "--output", path] + list(args),
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    with open(path) as f:
        return path, json.load(f), out.stdout


# 1. topology of the default three-module barrier, by hand
M, s, h, a = 3, 10.0, 4.0, 0.5
path, fem, text = make("barrier3", "--modules", "3", "--spacing", "10", "--height", "4",
                       "--mesh-size", "0.5", "--tilt-deg", "10")
per, rows = 20, 8                       # 10 / 0.5 meshes per module, 4 / 0.5 over the height
nx, nz = M * per + 1, rows + 1
nodes = np.array(fem["nodes"])
els = fem["elements"]
by_set = {}
for i, e in enumerate(els):
    by_set.setdefault(e["set"], []).append(i)
types = {st["name"]: st["type"] for st in fem["element_sets"]}
# net nodes, 2 anchors per support rope + 2 brake ends each, one upslope anchor per post,
# 2 lateral anchors
n_expect = nx * nz + 2 * 4 + (M + 1) + 2
check(len(nodes) == n_expect, "node count %d = grid %d x %d + 8 support-rope + %d upslope + 2 lateral" % (len(nodes), nx, nz, M + 1))
net_expect = (nx - 1) * (nz - 2) + (nx - 2) * (nz - 1)
counts = {k: len(v) for k, v in by_set.items()}
check(counts.get("net") == net_expect, "net meshes %s = (nx-1)(nz-2) + (nx-2)(nz-1) = %d" % (counts.get("net"), net_expect))
check(counts.get("top_rope") == nx + 1 and counts.get("bottom_rope") == nx + 1,
      "each support rope: %d segments through %d edge nodes" % (nx + 1, nx))
check(counts.get("edge_rope") == 2 * (nz - 1), "edge ropes: 2 x %d segments" % (nz - 1))
check(counts.get("post") == M + 1 and counts.get("upslope_rope") == M + 1, "one post and one upslope rope per post")
check(counts.get("lateral_rope") == 2 and counts.get("brake_support") == 4, "2 lateral ropes, 4 support-rope brakes")
check(types == {"net": "cable", "top_rope": "sliding_cable", "bottom_rope": "sliding_cable",
                "edge_rope": "sliding_cable", "upslope_rope": "brake", "lateral_rope": "cable",
                "post": "post", "brake_support": "brake"}, "element types per set: %s" % types)
gaps = {st["name"]: st.get("shackle_gap_m") for st in fem["element_sets"]}
check(all((gaps[n] == 0.05) == (types[n] == "sliding_cable") for n in gaps),
      "shackle contact (gap 0.05 m) on the sliding ropes only: %s" % gaps)
_, fem_nogap, _ = make("barrier3_nogap", "--modules", "1", "--shackle-gap", "0")
check(not any("shackle_gap_m" in st for st in fem_nogap["element_sets"]), "--shackle-gap 0: no contact written")
bad = subprocess.run(["/usr/bin/python3", script, "--output", os.path.join(tmp, "bad.json"),
                      "--mesh-size", "0.3", "--shackle-gap", "0.2"], capture_output=True, text=True)
check(bad.returncode == 2 and "--shackle-gap" in bad.stderr and "half the mesh size" in bad.stderr,
      "a shackle gap of 0.2 m on 0.3 m meshes refused: %s" % bad.stderr.strip().splitlines()[-1:])
ns = fem["node_sets"]
check(len(ns["anchors"]) == 4 + (M + 1) + 2 and len(ns["post_bases"]) == M + 1 and len(ns["post_tops"]) == M + 1,
      "node sets: %d anchors, %d post bases and tops" % (len(ns["anchors"]), M + 1))
check(len(ns["net"]) == nx * nz and len(ns["top_shackles"]) == nx - (M + 1), "net and shackle node sets")
c = nodes[ns["net_centre"][0]]
t = math.radians(10)
check(abs(c[0] - 15.0) < 1e-9 and abs(c[2] - 2.0 * math.cos(t)) < 1e-9 and abs(c[1] - 2.0 * math.sin(t)) < 1e-9,
      "net_centre in the middle of module 2 at mid-height: %s" % c)
check(fem["interface"] == {"element_sets": ["net"]}, "interface: the net only")
sup = fem["supports"]
check(sup == [{"nodes": ["anchors", "post_bases"], "dofs": "xyz"}], "supports: anchors and post bases pinned")

# 2. masses by hand: rho A L per set from the parameters
rho = 7850.0
A = lambda d: 0.58 * math.pi * d * d / 4.0
dx, dz = s / per, h / rows
sq = lambda p, q: math.dist(p, q)
L_net = (nx - 1) * (nz - 2) * dx + (nx - 2) * (nz - 1) * dz
top = [0, h * math.sin(t), h * math.cos(t)]
# top rope: anchor (-h, 0, 0), brake 1 m along the rope, then to the post top; the straight edge
L_top = 2 * (sq([-h, 0, 0], top) - 1.0) + M * s
L_bot = 2 * (h / 2 - 1.0) + M * s
L_up = sq([0, -h, 0], top)
L_lat = sq([-0.75 * h, 0, 0], top)
hand = {"net": rho * A(0.008) * L_net, "top_rope": rho * A(0.022) * L_top, "bottom_rope": rho * A(0.022) * L_bot,
        "edge_rope": rho * A(0.016) * 2 * h, "upslope_rope": (M + 1) * (rho * A(0.018) * L_up + 8.0),
        "lateral_rope": 2 * rho * A(0.018) * L_lat, "post": (M + 1) * rho * 3.88e-3 * h, "brake_support": 4 * 8.0}
# fem_solver's start-up summary per set (static variant below prints it)
spath, sfem, _ = make("barrier3_static", "--modules", "3", "--mesh-size", "0.5", "--analysis", "static")
out = subprocess.run([exe, spath, "--output", os.path.join(tmp, "static3")], capture_output=True, text=True)
summary = {}
for line in out.stdout.splitlines():
    if line.strip().startswith("set "):
        name = line.split()[1]
        summary[name] = (line.split("(")[1].split(")")[0], float(line.split("mass ")[1].split(" kg")[0]))
for name, m in hand.items():
    got = summary.get(name, (None, float("nan")))
    check(abs(got[1] - m) < 1e-5 * m, "%s mass %.6g kg (fem_solver) = %.6g kg by hand" % (name, got[1], m))
check(summary.get("brake_support", ("",))[0] == "brake" and summary.get("post", ("",))[0] == "post",
      "start-up summary names the element types: %s" % {k: v[0] for k, v in summary.items()})
# the static analysis: Newton alone meets dofs that only slack meshes hold (singular); each
# load step is then solved by pseudo-time steps, and the reactions balance the weight
settled = [l for l in out.stderr.splitlines() if "load steps solved by pseudo-time steps" in l]
check(out.returncode == 0 and len(settled) == 1,
      "static analysis of the taut-only net: exit %d, %s" % (out.returncode, settled or out.stderr[-300:]))
if out.returncode == 0:
    with h5py.File(os.path.join(tmp, "static3", "fem.h5")) as f:
        R = f["/output/reaction"][-1].sum(axis=0)
        L = f["/mesh/reference_length"][:]
        es = f["/mesh/element_set"][:]
    rhoA = [st["density_kg_m3"] * (st.get("area_m2") or A(st["diameter_m"])) for st in sfem["element_sets"]]
    W = 9.81 * sum(rhoA[k] * l for k, l in zip(es, L))
    err = np.abs(R - np.array([0.0, 0.0, W])).max() / W
    check(err < 1e-8, "static analysis: reactions balance the weight to %.2g of it (at most 1e-8)" % err)

# 3. chains: each support rope one run of consecutive segments, brake at each end, anchor beyond
fixed = set(ns["anchors"]) | set(ns["post_bases"])
for rope, row in (("top_rope", nz - 1), ("bottom_rope", 0)):
    seg = [els[i]["nodes"] for i in by_set[rope]]
    one = all(seg[k][1] == seg[k + 1][0] for k in range(len(seg) - 1)) and by_set[rope] == list(
        range(by_set[rope][0], by_set[rope][0] + len(seg)))
    chain = [seg[0][0]] + [q[1] for q in seg]
    edge = [i * nz + row for i in range(nx)]
    check(one and len(set(chain)) == len(chain), "%s: one chain of %d nodes, no node twice" % (rope, len(chain)))
    check(chain[1:-1] == edge, "%s: through every node of its net edge in order" % rope)
    ends = []
    for end in (chain[0], chain[-1]):
        br = [els[i]["nodes"] for i in by_set["brake_support"] if end in els[i]["nodes"]]
        other = [n for b in br for n in b if n != end]
        ends.append(len(br) == 1 and other[0] in ns["anchors"] and end not in fixed)
    check(all(ends), "%s: each end a free node joined by one brake to an anchor" % rope)
# posts: base pinned (in post_bases, xyz), top free, held by an upslope rope and the top rope
for k, i in enumerate(by_set["post"]):
    b, tp = els[i]["nodes"]
    held = [els[j]["set"] for j in range(len(els)) if tp in els[j]["nodes"]]
    check(b in ns["post_bases"] and tp in ns["post_tops"] and tp not in fixed and "upslope_rope" in held
          and "top_rope" in held and abs(math.dist(nodes[b], nodes[tp]) - h) < 1e-9,
          "post %d: hinged base, free top on the top rope and an upslope rope, length h" % k)

# 4. equilibrium under self-weight and prestress: the dynamic run starts at rest in it
#    (make_barrier's default analysis.initial_state "static") and stays there
dpath, dfem, _ = make("barrier1", "--modules", "1", "--mesh-size", "0.5", "--dt", "0.01", "--end-time", "0.1",
                      "--rayleigh-tau", "10", "--rayleigh-kappa", "2e-5", "--output-interval", "5")
check(dfem["rayleigh"] == {"tau_per_s": 10.0, "kappa_s": 2e-5}, "Rayleigh damping as given: %s" % dfem["rayleigh"])
check(dfem["analysis"].get("initial_state") == "static", "initial_state static by default: %s" % dfem["analysis"])
out = subprocess.run([exe, dpath, "--output", os.path.join(tmp, "relax1")], capture_output=True, text=True)
check(out.returncode == 0, "fem_solver runs the one-module barrier (exit %d): %s" % (out.returncode, out.stderr[-300:]))
if out.returncode == 0:
    with h5py.File(os.path.join(tmp, "relax1", "fem.h5")) as f:
        R = f["/output/reaction"][:].sum(axis=1)
        u = f["/output/displacement"][:]
        L = f["/mesh/reference_length"][:]
        es = f["/mesh/element_set"][:]
        v = f["/output/velocity"][:]
    rhoA = [st["density_kg_m3"] * (st.get("area_m2") or A(st["diameter_m"])) for st in dfem["element_sets"]]
    W = 9.81 * sum(rhoA[k] * l for k, l in zip(es, L))
    err = np.abs(R - np.array([0.0, 0.0, W])).max() / W
    print("weight %.6g N, reactions at t = 0 %s N, at the end %s N; largest speed %.3g m/s, "
          "largest move %.3g m" % (W, R[0], R[-1], np.abs(v).max(), np.abs(u - u[0]).max()))
    # Sum R = sum(M a + C v) - W at every step; at rest the first term vanishes, and the run
    # starts there. (Released from the generated geometry, 12 s of damped dynamics left the
    # slack meshes rattling at ~3 mm/s, 1.6e-5 W off.)
    check(err < 1e-8, "reactions balance the weight at every output step: %.2g of it (at most 1e-8)" % err)
    check(np.abs(v).max() < 1e-8 and np.abs(u - u[0]).max() < 1e-9,
          "and the barrier hangs still: speed %.2g m/s, move %.2g m" % (np.abs(v).max(), np.abs(u - u[0]).max()))
    check(np.linalg.norm(u[0], axis=1).max() > 0.01,
          "it sagged from the generated geometry first: %.3f m" % np.linalg.norm(u[0], axis=1).max())

# 5. ring net: fem_solver reads it and runs
rpath, rfem, _ = make("ring1", "--modules", "1", "--mesh-size", "0.5", "--net", "ring", "--dt", "0.01",
                      "--end-time", "0.05")
check(rfem["element_sets"][0]["type"] == "ring", "ring net: the net set is of type ring")
out = subprocess.run([exe, rpath, "--output", os.path.join(tmp, "ring1")], capture_output=True, text=True)
check(out.returncode == 0 and "set net (ring)" in out.stdout, "fem_solver reads and runs the ring-net barrier")

# 6. bad input: a clear message, non-zero exit
bad = subprocess.run(["/usr/bin/python3", script, "--output", os.path.join(tmp, "bad.json"), "--spacing", "-1"],
                     capture_output=True, text=True)
check(bad.returncode == 2 and "--spacing" in bad.stderr, "--spacing -1 refused naming the option")

print("%d failure(s)" % len(failures))
raise SystemExit(1 if failures else 0)
