# resume_lib.sh — sourced by tests/coupler/test_resume*.sh (after tests/e2e_lib.sh): one
# checkpoint/resume check of a real coupled run started by scripts/run_case.sh.
#
# resume_check NAME CASE_DIR MODE FILES [run_case.sh arguments ...]
#   A: the case uninterrupted into $NC_TMP/NAME.a;
#   B: the same into $NC_TMP/NAME.b, stopped once B/checkpoint/latest.json appears:
#      MODE int  -> SIGINT to run_case.sh (exit 130, as a user's Ctrl-C),
#      MODE kill -> SIGKILL to its whole process group (a crash: nothing is shut down);
#      then `run_case.sh --resume B` (the programs of the first run, nothing else given).
#   Every dataset of the HDF5 files FILES (space separated, e.g. "coupling.h5 fem.h5") of A
#   and B must have the same shape and the same bytes, except the wall-clock datasets listed
#   in WALL_CLOCK below; so must the other result files in FILES (CSV, iterations.log).
# The caller must `set -m` (each run_case.sh in its own process group, SIGINT not ignored).

# datasets that hold wall-clock times (not reproducible), per file
WALL_CLOCK="coupling.h5:/timing/total"

resume_check() {
  local name=$1 case_dir=$2 mode=$3 files=$4
  shift 4
  local a=$NC_TMP/$name.a b=$NC_TMP/$name.b
  scripts/run_case.sh "$case_dir" --out "$a" "$@" > "$a.out" 2>&1 \
    || { tail -n 20 "$a.out"; fail "$name: uninterrupted run failed"; }
  [ -f "$a/checkpoint/latest.json" ] || fail "$name: the uninterrupted run took no checkpoint: $(grep -m 3 'checkpoint' "$a/coupler.log")"

  scripts/run_case.sh "$case_dir" --out "$b" "$@" > "$b.out" 2>&1 &
  local rpid=$! i
  for i in $(seq 1200); do
    [ -f "$b/checkpoint/latest.json" ] && break
    kill -0 "$rpid" 2>/dev/null || break
    sleep 0.05
  done
  kill -0 "$rpid" 2>/dev/null || fail "$name: run B ended before it was stopped (make the run longer)"
  [ -f "$b/checkpoint/latest.json" ] || fail "$name: no checkpoint/latest.json after 60 s"
  local rc
  if [ "$mode" = int ]; then
    kill -INT "$rpid"; wait "$rpid"; rc=$?
    [ "$rc" -eq 130 ] || fail "$name: run_case.sh after SIGINT: exit $rc, expected 130: $(tail -n 3 "$b.out")"
  else
    kill -KILL -- "-$rpid"; wait "$rpid"; rc=$?
    [ "$rc" -eq 137 ] || fail "$name: run_case.sh after SIGKILL: exit $rc"
    sleep 0.2   # the group is gone; nothing ran its clean-up
  fi
  local stopped_at
  stopped_at=$(sed -n 's/.*"checkpoint":[[:space:]]*"\([^"]*\)".*/\1/p' "$b/checkpoint/latest.json")
  scripts/run_case.sh --resume "$b" > "$b.resume.out" 2>&1 \
    || { tail -n 20 "$b.resume.out" "$b"/*.log; fail "$name: run_case.sh --resume failed"; }
  grep -q "resuming from checkpoint $stopped_at" "$b/coupler.log" \
    || fail "$name: the coupler did not resume from $stopped_at: $(head -n 5 "$b/coupler.log")"
  # the summary's wall time adds the part before the checkpoint: never below the waiting times
  grep -q "^coupler: wall time .*coupler itself -" "$b/coupler.log" \
    && fail "$name: the resumed run's wall-time split is negative: $(grep '^coupler: wall time' "$b/coupler.log")"
  "$PY" - "$a" "$b" "$WALL_CLOCK" $files <<'PY' || fail "$name: the resumed run differs from the uninterrupted one"
import sys, h5py, numpy as np
a, b, wall, files = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
skip = {}
for w in wall.split():
    f, d = w.split(":", 1)
    skip.setdefault(f, set()).add(d)
bad, compared = [], 0
for name in files:
    if not name.endswith(".h5"):
        ta, tb = open(a + "/" + name, "rb").read(), open(b + "/" + name, "rb").read()
        compared += 1
        if ta != tb:
            bad.append("%s: files differ (%d and %d bytes)" % (name, len(ta), len(tb)))
        continue
    with h5py.File(a + "/" + name, "r") as fa, h5py.File(b + "/" + name, "r") as fb:
        def sets(f):
            out = {}
            f.visititems(lambda p, o: out.__setitem__("/" + p, o) if isinstance(o, h5py.Dataset) else None)
            return out
        da, db = sets(fa), sets(fb)
        if set(da) != set(db):
            bad.append("%s: datasets only in A %s, only in B %s" % (name, sorted(set(da) - set(db)), sorted(set(db) - set(da))))
        for p in sorted(set(da) & set(db)):
            if p in skip.get(name, ()):
                continue
            x, y = da[p][()], db[p][()]
            compared += 1
            if np.shape(x) != np.shape(y):
                bad.append("%s%s: shape %s vs %s" % (name, p, np.shape(x), np.shape(y)))
            elif np.asarray(x).tobytes() != np.asarray(y).tobytes():
                xa, ya = np.asarray(x).ravel(), np.asarray(y).ravel()
                k = next(i for i in range(len(xa)) if xa[i:i+1].tobytes() != ya[i:i+1].tobytes())
                bad.append("%s%s: differs first at value %d: %r vs %r" % (name, p, k, xa[k], ya[k]))
for m in bad:
    print("  " + m)
if bad:
    sys.exit(1)
with h5py.File(a + "/coupling.h5", "r") as f:
    steps = f["/steps/time"].shape[0]
print("%s: resumed run identical to the uninterrupted one (%d datasets/files, %d steps)" % (b, compared, steps))
PY
}
