#!/usr/bin/env python3
"""Writes the seed corpus of the protocol decoder fuzzer (layout: see fuzz_decode.c)."""
import json, os, struct, sys

out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "corpus")
os.makedirs(out, exist_ok=True)

def pack(header, frames):
    head = bytes([len(frames)]) + b"".join(struct.pack("<H", len(f)) for f in frames)
    return head + b"".join(frames) + json.dumps(header).encode()

def f64(values):
    return struct.pack("<%dd" % len(values), *values)

def i32(values):
    return struct.pack("<%di" % len(values), *values)

seeds = {
    "hello": pack({"type": "hello", "version": 1, "role": "coupler", "name": "netcouple coupler"}, []),
    "hello_reply": pack({"type": "hello", "version": 1, "reply": True, "role": "fem", "text": "restore"}, []),
    "begin_step": pack({"type": "begin_step", "version": 1, "step": 3, "time": 0.003, "dt": 0.001}, []),
    "solve_fem": pack({"type": "solve", "version": 1, "step": 3, "iteration": 2, "time": 0.003, "dt": 0.001,
                       "arrays": [{"name": "force", "dtype": "f64", "shape": [2, 3]}]}, [f64([1, 2, 3, 4, 5, 6])]),
    "solve_reply": pack({"type": "solve", "version": 1, "reply": True, "status": "ok",
                         "arrays": [{"name": "displacement", "dtype": "f64", "shape": [1, 3]},
                                    {"name": "velocity", "dtype": "f64", "shape": [1, 3]}],
                         "values": {"newton_iterations": 3, "residual_norm": 1e-9}},
                        [f64([0.1, 0.2, 0.3]), f64([1, 2, 3])]),
    "interface": pack({"type": "interface", "version": 1, "reply": True,
                       "arrays": [{"name": "node_ids", "dtype": "i32", "shape": [3]},
                                  {"name": "coordinates", "dtype": "f64", "shape": [3, 3]},
                                  {"name": "elements", "dtype": "i32", "shape": [2, 2]}]},
                      [i32([0, 1, 2]), f64([0, 0, 0, 1, 0, 0, 2, 0, 0]), i32([0, 1, 1, 2])]),
    "error": pack({"type": "error", "version": 1, "reply": True, "status": "error",
                   "text": "Newton did not converge"}, []),
    "nan": pack({"type": "solve", "version": 1, "arrays": [{"name": "force", "dtype": "f64", "shape": [1]}]},
                [f64([float("nan")])]),
    "short_frame": pack({"type": "solve", "version": 1, "arrays": [{"name": "u", "dtype": "f64", "shape": [4]}]},
                        [f64([1, 2])]),
    "version2": pack({"type": "solve", "version": 2}, []),
}
for name, data in seeds.items():
    with open(os.path.join(out, name), "wb") as f:
        f.write(data)
