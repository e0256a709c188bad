#!/usr/bin/env python3
"""Writes the seed corpus of the coupler.json fuzz target."""
import json, os

here = os.path.dirname(os.path.abspath(__file__))
docs = {
    "weak.json": {"scheme": "weak", "dt": 1e-3, "end_time": 0.5},
    "strong.json": {"scheme": "strong", "dt": 1e-3, "end_time": 1.0, "max_iterations": 30, "tolerance": 1e-6,
                    "relaxation": {"method": "aitken", "initial": 0.5}, "predictor": "linear",
                    "step_control": {"enabled": True}, "timeouts": {"reply_s": 60},
                    "fem": {"endpoint": "tcp://127.0.0.1:5555"}, "dem": {"endpoint": "tcp://127.0.0.1:5556"}},
    "iqn.json": {"scheme": "strong", "dt": 2e-3, "end_time": 0.2, "relaxation": {"method": "iqn"}},
    "late_start.json": {"scheme": "weak", "dt": 1e-3, "start_time": 1e17, "end_time": 1.0000001e17},
}
for name, doc in docs.items():
    open(os.path.join(here, "corpus_coupler_json", name), "w").write(json.dumps(doc))
open(os.path.join(here, "corpus_coupler_json", "huge_number.json"), "w").write('{"scheme": "weak", "dt": 1e-3, "end_time": 1e400}')
open(os.path.join(here, "corpus_coupler_json", "duplicate.json"), "w").write('{"scheme": "weak", "dt": 1e-3, "end_time": 1, "dt": 1e-6}')
