#!/usr/bin/env bash
# Every case under cases/ is a folder with fem.json, dem.json, coupler.json and a README.md,
# and every file those inputs name (meshes, STL terrain) is in the folder. Checked statically:
# the JSON must parse, and each string value ending in .msh/.stl/.json is a file next to it.
set -u
PY=${PYTHON:-/usr/bin/python3}
"$PY" - <<'PY'
import glob, json, os, sys
bad = []
cases = sorted(d for d in glob.glob("cases/*/") if os.path.isdir(d))
assert len(cases) >= 7, "expected the paper's 7 cases, found %d" % len(cases)
def strings(node):
    if isinstance(node, dict):
        for v in node.values(): yield from strings(v)
    elif isinstance(node, list):
        for v in node: yield from strings(v)
    elif isinstance(node, str):
        yield node
for d in cases:
    for f in ("fem.json", "dem.json", "coupler.json", "README.md"):
        if not os.path.isfile(d + f):
            bad.append(d + f + " missing")
    for f in ("fem.json", "dem.json", "coupler.json"):
        try:
            doc = json.load(open(d + f))
        except (OSError, ValueError) as e:
            bad.append("%s%s: %s" % (d, f, e)); continue
        for s in strings(doc):
            if s.lower().endswith((".msh", ".stl")) and not os.path.isfile(os.path.join(d, s)):
                bad.append("%s%s names %s, not in the folder" % (d, f, s))
    print("%-26s ok" % d if not any(b.startswith(d) for b in bad) else "%-26s FAILED" % d)
if bad:
    print("\n".join("FAIL: " + b for b in bad)); sys.exit(1)
PY
