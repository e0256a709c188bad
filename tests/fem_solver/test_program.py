#!/usr/bin/python3
"""test_program — the fem_solver program end to end (script test, run by scripts/run_tests.sh).

Runs the documented examples with $NC_BIN/fem_solver and checks: exit codes, the HDF5
layout users rely on (/mesh, /output series, /monitor/time, /monitor/node_ids,
/monitor/displacement), the static answer of the paper's 7.2 cable (w = 0.303837 m from the
closed form in test_static.c, tolerance 1e-6 m), the XDMF file (tests/xdmf_check.py: it
describes fem.h5 exactly, one grid per output time; and the check fails on corrupted copies),
bad inputs (clear message naming the file, exit 1), usage errors (exit 2), SIGTERM (clean
stop: exit 130, results readable), and a rope above its breaking load (two bars in series
under 10 kN on each of their two free nodes: 20 kN in the first, breaking load 15 kN): the
warning on stderr and in fem.h5, exit 0, or 3 with analysis.fail_on_overload; the option
without any breaking load is warned about.
"""
import json
import os
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

try:
    import h5py
    import numpy as np
except ImportError:
    print("h5py/numpy missing: skipped")
    sys.exit(77)

ROOT = os.environ.get("NC_ROOT", ".")
sys.path.insert(0, os.path.join(ROOT, "tests"))
from xdmf_check import check_xdmf as check_xdmf_file, grid_counts, self_test  # noqa: E402
BIN = os.path.join(os.environ["NC_BIN"], "fem_solver")
TMP = os.environ["NC_TMP"]
EX = os.path.join(ROOT, "fem_solver", "examples")
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL:", what)


def run(args, timeout=300):
    return subprocess.run([BIN] + args, capture_output=True, text=True, timeout=timeout)


def check_xdmf(out, n_nodes, n_elems, n_steps):
    """fem.xdmf describes fem.h5 exactly (tests/xdmf_check.py): one grid per row of
    /output/time at that time, n_nodes points and n_elems cells, data only from fem.h5."""
    path = os.path.join(out, "fem.xdmf")
    for p in check_xdmf_file(path, "/output/time"):
        check(False, p)
    counts = grid_counts(path)
    check(counts == {"net": n_steps}, "xdmf grids %s, expected {'net': %d}" % (counts, n_steps))
    root = ET.parse(path).getroot()
    for item in root.iter("DataItem"):
        if item.get("Format") == "HDF":
            check(item.text.strip().split(":")[0] == "fem.h5", "xdmf refers to " + item.text.strip())
    grid = root.find("./Domain/Grid/Grid")
    check(grid.find("Topology").get("NumberOfElements") == str(n_elems), "xdmf cells")
    check(grid.find("Geometry/DataItem").get("Dimensions") == "%d 3" % n_nodes, "xdmf points")


def net_dynamic(name, end_time_s):
    """examples/net_dynamic.json ending at end_time_s, written to TMP/<name>.json; returns that
    path and the output folder TMP/<name>."""
    cfg = json.load(open(os.path.join(EX, "net_dynamic.json")))
    cfg["analysis"]["end_time_s"] = end_time_s
    path = os.path.join(TMP, name + ".json")
    with open(path, "w") as f:
        json.dump(cfg, f)
    return path, os.path.join(TMP, name)


def test_static_example():
    out = os.path.join(TMP, "static")
    r = run([os.path.join(EX, "cable_static.json"), "--output", out])
    check(r.returncode == 0, "cable_static exit %d: %s" % (r.returncode, r.stderr))
    with h5py.File(os.path.join(out, "fem.h5"), "r") as f:
        check(f["/mesh/coordinates"].shape == (4, 3), "mesh/coordinates shape")
        check(f["/mesh/elements"].shape == (3, 2) and f["/mesh/elements"].dtype == np.int32, "mesh/elements")
        check(f["/output/time"].shape == (11,), "output/time has 11 rows (load 0, 0.1 .. 1)")
        for name, shape in (("displacement", (11, 4, 3)), ("velocity", (11, 4, 3)),
                            ("position", (11, 4, 3)), ("axial_force", (11, 3))):
            check(f["/output/" + name].shape == shape, "output/%s shape %s" % (name, f["/output/" + name].shape))
        check(list(f["/monitor/node_ids"][:]) == [1, 2], "monitor/node_ids")
        check(f["/monitor/time"].shape == (11,), "monitor/time rows")
        md = f["/monitor/displacement"][:]
        check(md.shape == (11, 2, 3), "monitor/displacement shape")
        w = -md[-1, 0, 2]
        check(abs(w - 0.303836935) < 1e-6, "7.2 static deflection %.9f vs closed form 0.303836935" % w)
        pos = f["/output/position"][-1]
        check(np.allclose(pos, f["/mesh/coordinates"][:] + f["/output/displacement"][-1]), "position = X + u")
    check_xdmf(out, 4, 3, 11)
    # the XDMF check itself fails on broken copies of this result
    for missed in self_test(out, "fem.xdmf", "/output/time", TMP):
        check(False, "xdmf_check self-test: " + missed)


def test_dynamic_and_gmsh():
    path, out = net_dynamic("net", 0.1)
    r = run([path, "--output", out])
    check(r.returncode == 0, "net_dynamic exit %d: %s" % (r.returncode, r.stderr))
    with h5py.File(os.path.join(out, "fem.h5"), "r") as f:
        check(f["/monitor/time"].shape == (51,), "monitor every step: %s" % (f["/monitor/time"].shape,))
        check(f["/output/time"].shape == (6,), "output every 10 steps + t=0: %s" % (f["/output/time"].shape,))
        t = f["/monitor/time"][:]
        check(abs(t[-1] - 0.1) < 1e-12, "end time")
        w = f["/monitor/displacement"][:, 0, 2]
        check(w[-1] < -0.01, "net sags under its weight and the load: %g" % w[-1])
    check_xdmf(out, 441, 840, 6)
    out = os.path.join(TMP, "gmsh")
    r = run([os.path.join(EX, "cable_gmsh.json"), "--output", out])
    check(r.returncode == 0, "cable_gmsh exit %d: %s" % (r.returncode, r.stderr))
    with h5py.File(os.path.join(out, "fem.h5"), "r") as f:
        # same cable as cable_static (node numbering differs): same deflection
        w = -f["/output/displacement"][-1][:, 2].min()
        check(abs(w - 0.303836935) < 1e-6, "gmsh cable deflection %.9f" % w)


def test_errors():
    bad = os.path.join(TMP, "bad.json")
    open(bad, "w").write('{"nodes": [[0,0,0],[1,0,0]], "elements": [[0,1]], "element_sets": '
                         '[{"youngs_modulus_pa": -3, "area_m2": 1e-4}]}')
    r = run([bad, "--output", os.path.join(TMP, "bad")])
    check(r.returncode == 1, "negative E: exit %d" % r.returncode)
    check("bad.json" in r.stderr and "youngs_modulus_pa" in r.stderr and "> 0" in r.stderr,
          "negative E message: " + r.stderr)
    r = run([os.path.join(TMP, "missing.json"), "--output", os.path.join(TMP, "x")])
    check(r.returncode == 1 and "missing.json" in r.stderr, "missing file: " + r.stderr)
    open(bad, "w").write('{"nodes": [[0,0,0],[1,0,0]], "elements": [[0,1]]')
    r = run([bad, "--output", os.path.join(TMP, "bad")])
    check(r.returncode == 1 and "bad.json" in r.stderr and "malformed" in r.stderr, "malformed: " + r.stderr)
    r = run([os.path.join(EX, "cable_static.json")])
    check(r.returncode == 2 and "--output" in r.stderr, "no --output: exit %d" % r.returncode)
    r = run([os.path.join(EX, "cable_static.json"), "--output", TMP, "--bogus"])
    check(r.returncode == 2, "unknown option: exit %d" % r.returncode)
    # a static flat net without prestress under its own weight: singular for Newton, solved by
    # pseudo-time steps instead (it sags 0.73 m), and the log says so
    cfg = json.load(open(os.path.join(EX, "angled_net_fem.json")))
    cfg["analysis"] = {"type": "static"}
    path = os.path.join(TMP, "flat.json")
    json.dump(cfg, open(path, "w"))
    r = run([path, "--output", os.path.join(TMP, "flat")])
    check(r.returncode == 0 and "1 of 1 load steps solved by pseudo-time steps" in r.stderr,
          "flat net under its weight: exit %d: %s" % (r.returncode, r.stderr[-300:]))
    with h5py.File(os.path.join(TMP, "flat", "fem.h5"), "r") as f:
        sag = float(np.abs(f["/output/displacement"][-1]).max())
    check(0.5 < sag < 1.0, "flat net under its weight sags %.3f m" % sag)
    # without mass (density 0, a point load on an interior node) there is nothing to step in
    # pseudo-time: singular, the message names a node and why
    cfg["element_sets"][0]["density_kg_m3"] = 0
    cfg["point_loads"] = [{"nodes": [220], "force_n": [0, 0, -10]}]
    json.dump(cfg, open(path, "w"))
    r = run([path, "--output", os.path.join(TMP, "flat0")])
    check(r.returncode == 1 and "node " in r.stderr and "singular" in r.stderr
          and "no mass" in r.stderr, "singular: " + r.stderr[-400:])


def test_sigterm():
    path, out = net_dynamic("long", 1000.0)
    p = subprocess.Popen([BIN, path, "--output", out], stderr=subprocess.PIPE, text=True)
    h5 = os.path.join(out, "fem.h5")
    for _ in range(300):
        if os.path.exists(os.path.join(out, "fem.xdmf")):
            break
        time.sleep(0.1)
    time.sleep(1.0)
    p.send_signal(signal.SIGTERM)
    try:
        _, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        check(False, "no exit after SIGTERM")
        return
    check(p.returncode == 130, "SIGTERM exit %d: %s" % (p.returncode, err))
    with h5py.File(h5, "r") as f:
        n = f["/monitor/time"].shape[0]
        check(n > 1 and f["/monitor/displacement"].shape[0] == n, "monitor rows after SIGTERM: %d" % n)
        k = f["/output/time"].shape[0]
    check_xdmf(out, 441, 840, k)


def test_overload():
    model = {"nodes": [[0, 0, 0], [1, 0, 0], [2, 0, 0]],
             "elements": [{"nodes": [0, 1], "set": "net"}, {"nodes": [1, 2], "set": "net"}],
             "element_sets": [{"name": "net", "youngs_modulus_pa": 1e11, "area_m2": 1e-4,
                               "breaking_load_n": 15000, "behaviour": "truss"}],
             "supports": [{"nodes": [0]}, {"nodes": [1, 2], "dofs": "yz"}],
             "point_loads": [{"nodes": [1, 2], "force_n": [10000, 0, 0]}],
             "analysis": {"type": "static", "load_steps": 4}}
    warning = ("warning: set net: 1 element exceeded breaking_load_n 15000 N (first at load factor 1); "
               "largest 20000 N (1.33x) in element 0 at load factor 1; the model has no rope failure")
    for fail in (False, True):
        model["analysis"]["fail_on_overload"] = fail
        path = os.path.join(TMP, "overload.json")
        json.dump(model, open(path, "w"))
        out = os.path.join(TMP, "overload_%d" % fail)
        r = run([path, "--output", out])
        check(r.returncode == (3 if fail else 0), "overload exit %d: %s" % (r.returncode, r.stderr))
        check(warning in r.stderr, "overload warning missing: " + r.stderr)
        with h5py.File(os.path.join(out, "fem.h5"), "r") as f:
            text = f.attrs["overload"]
            text = text.decode() if isinstance(text, bytes) else text
            check(f.attrs["overloaded_elements"] == 1 and warning in text,
                  "fem.h5 overload attributes %s" % dict(f.attrs))
            check(abs(f["element_sets/peak_axial_force"][0] - 2e4) < 1e-9 * 2e4
                  and f["element_sets/peak_axial_force"].attrs["units"] in (b"N", "N"),
                  "peak force %s" % f["element_sets/peak_axial_force"][()])
    # the option without any breaking load can never fire: warned, naming the field
    del model["element_sets"][0]["breaking_load_n"]
    json.dump(model, open(path, "w"))
    r = run([path, "--output", os.path.join(TMP, "overload_none")])
    check(r.returncode == 0, "overload without breaking loads: exit %d: %s" % (r.returncode, r.stderr))
    check("analysis.fail_on_overload: no element set gives breaking_load_n" in r.stdout + r.stderr,
          "no warning for fail_on_overload without breaking loads: " + r.stdout + r.stderr)


def test_undamped_coupling_warning():
    """A coupled run (--endpoint) whose integrator has no numerical damping and takes the
    coupling force at the step's end is warned about at start, naming the file and the fix;
    a damped integrator (Bossak -0.3), the step-constant load or a standalone run are not."""
    base = {"nodes": [[0, 0, 0], [1, 0, 0], [2, 0, 0]], "elements": [[0, 1], [1, 2]],
            "element_sets": [{"youngs_modulus_pa": 1e9, "area_m2": 1e-4, "density_kg_m3": 7850,
                              "prestress_pa": 1e6}],
            "supports": [{"nodes": [0, 2]}]}
    cases = [({"type": "dynamic"}, True, True),
             ({"type": "dynamic", "integrator": "generalized_alpha", "rho_inf": 1.0}, True, True),
             ({"type": "dynamic", "integrator": "bossak", "alpha_b": -0.3}, True, False),
             ({"type": "dynamic", "coupling_load": "step_constant"}, True, False),
             ({"type": "dynamic", "end_time_s": 0.01}, False, False)]
    for k, (analysis, coupled, warned) in enumerate(cases):
        path = os.path.join(TMP, "undamped_%d.json" % k)
        json.dump(dict(base, analysis=analysis), open(path, "w"))
        args = [path, "--output", os.path.join(TMP, "undamped_%d" % k)]
        if coupled:   # no coupler comes: the idle timeout ends it
            args += ["--endpoint", "tcp://127.0.0.1:*", "--idle-timeout", "0.2"]
        r = run(args)
        said = "warning: %s: analysis: a coupled run with gamma 0.5" % path in r.stderr
        check(said == warned and "integrator \"bossak\" with alpha_b -0.3" in r.stderr if warned
              else not said, "%s coupled=%s: warned %s, expected %s: %s"
              % (analysis, coupled, said, warned, r.stderr[-300:]))


def test_check():
    """--check reads and checks the input and runs nothing: exit 0 and the summary for a valid
    input (no --output needed, no folder made), exit 1 naming file and field for a bad one;
    with --endpoint the coupled run's warnings come too, and nothing is bound."""
    out = os.path.join(TMP, "check_out")
    r = run([os.path.join(EX, "cable_static.json"), "--check", "--output", out])
    check(r.returncode == 0 and "valid (checked only, nothing run)" in r.stdout
          and not os.path.exists(out), "--check valid: exit %d: %s %s" % (r.returncode, r.stdout, r.stderr))
    bad = os.path.join(TMP, "bad_check.json")
    open(bad, "w").write('{"nodes": [[0,0,0],[1,0,0]], "elements": [[0,1]], "element_sets": '
                         '[{"youngs_modulus_pa": 1e11, "area_m2": 1e-4}], "analysis": {"dt": 1}}')
    r = run([bad, "--check"])
    check(r.returncode == 1 and "bad_check.json" in r.stderr and "analysis.dt: unknown key" in r.stderr
          and "valid" not in r.stdout, "--check bad: exit %d: %s" % (r.returncode, r.stderr))
    path = os.path.join(TMP, "undamped_0.json")   # written by test_undamped_coupling_warning
    r = run([path, "--check", "--endpoint", "tcp://127.0.0.1:*"], timeout=10)
    check(r.returncode == 0 and "a coupled run with gamma 0.5" in r.stderr,
          "--check --endpoint: exit %d: %s" % (r.returncode, r.stderr[-300:]))


for test in (test_static_example, test_dynamic_and_gmsh, test_errors, test_sigterm, test_overload,
             test_undamped_coupling_warning, test_check):
    print("--", test.__name__)
    test()
print("%d failure(s)" % len(failures))
sys.exit(1 if failures else 0)
