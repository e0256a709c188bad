"""test_study_reuse — scripts/study.py reuses a finished run only when it would compute the
same thing now: the same programs, the same case folder, the same --set options.

A study continues an interrupted one by reusing the runs it finds in its folder. A run's
label alone does not say which code or settings made it, so a study re-run after a change
of the programs would mix old runs in. Each run's done.json carries a stamp (a digest of the
programs run_case.sh runs, run_case.sh itself and the case folder, and the --set list), and
a run whose stamp differs is run again.

Runs cases/rest_position for 0.06 s (two steps of 3e-2 s; about 1 s each) with:
  - the same stamp twice: the second call reuses the results (coupling.h5 not rewritten);
  - another --set list: run again;
  - the same programs from another folder: reused; with one byte more in the coupler (an
    ELF file runs with trailing bytes): run again, then reused with those programs;
  - a done.json of the former script (no stamp): run again;
  - a timed-out run asked again with another wall-time cap: run again.
"""
import contextlib
import io
import json
import os
import shutil
import sys

root = os.environ["NC_ROOT"]
tmp = os.environ["NC_TMP"]
sys.path.insert(0, os.path.join(root, "scripts"))
import study  # noqa: E402

failures = []


def check(cond, what):
    print(("ok:   " if cond else "FAIL: ") + what)
    if not cond:
        failures.append(what)


SETS = ["coupler.end_time=0.06", "fem.analysis.end_time_s=0.06"]


def call(label, sets, timeout_s=None):
    """study.run with its printed lines captured; returns (ok, printed text, coupling.h5 mtime)."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        _, run_dir, _, ok = study.run("rest_position", label, sets, tmp, None, timeout_s)
    h5 = os.path.join(run_dir, "coupling.h5")
    return ok, out.getvalue(), os.stat(h5).st_mtime_ns if os.path.exists(h5) else None


ok, text, first = call("a", SETS)
check(ok and first is not None, "a first run completes (%r)" % text)
with open(os.path.join(tmp, "a", "done.json")) as f:
    stamp = json.load(f).get("stamp", {})
check(stamp.get("sets") == SETS and len(stamp.get("code", "")) == 64,
      "done.json carries the --set list and a sha256 code digest: %r" % stamp)

ok, text, again = call("a", SETS)
check(ok and again == first and "run again" not in text,
      "the same stamp reuses the results (coupling.h5 not rewritten)")

ok, text, other = call("a", SETS + ["dem.materials.0.restitution=0.3"])
check(ok and other != first and "other --set options" in text,
      "another --set list runs again and says why (%r)" % text.strip())

# the same programs copied to another folder: the same stamp (names and contents count, not
# where they are); then one byte more in the coupler: another build
bin_copy = os.path.join(tmp, "bin_copy")
os.makedirs(bin_copy)
for program in study.PROGRAMS:
    shutil.copy2(os.path.join(os.environ.get("NC_BIN", os.path.join(root, "bin")), program), bin_copy)
os.environ["NC_BIN"] = bin_copy
study.code_digest.cache_clear()
ok, text, copied = call("a", SETS + ["dem.materials.0.restitution=0.3"])
check(ok and copied == other and "run again" not in text,
      "the same programs from another folder reuse the results (%r)" % text.strip())
with open(os.path.join(bin_copy, "coupler"), "ab") as f:
    f.write(b"\0")
study.code_digest.cache_clear()
ok, text, rebuilt = call("a", SETS + ["dem.materials.0.restitution=0.3"])
check(ok and rebuilt != other and "the programs, the launcher or the case's inputs changed" in text,
      "changed programs run again and say why (%r)" % text.strip())
ok, text, kept = call("a", SETS + ["dem.materials.0.restitution=0.3"])
check(ok and kept == rebuilt and "run again" not in text, "and are reused with those programs")

# a done.json written by the former script: no stamp
done = os.path.join(tmp, "a", "done.json")
with open(done) as f:
    info = json.load(f)
del info["stamp"]
with open(done, "w") as f:
    json.dump(info, f)
ok, text, legacy = call("a", SETS + ["dem.materials.0.restitution=0.3"])
check(ok and legacy != kept and "no stamp" in text, "a done.json without a stamp runs again (%r)" % text.strip())

# a run recorded as stopped at its wall-time cap, asked with another cap
with open(done) as f:
    info = json.load(f)
info["timed_out"], info["ok"] = True, False
with open(done, "w") as f:
    json.dump(info, f)
ok, text, _ = call("a", SETS + ["dem.materials.0.restitution=0.3"], timeout_s=120)
check(ok and "another wall-time cap" in text, "a timed-out run asked with another cap runs again (%r)" % text.strip())

if failures:
    print("%d check(s) failed" % len(failures))
    sys.exit(1)
print("all checks passed")
