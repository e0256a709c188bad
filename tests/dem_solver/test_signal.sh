#!/usr/bin/env bash
# test_signal — SIGTERM during a standalone run: dem_solver stops cleanly (exit 130) and the
# results written so far are readable (HDF5 opens, XDMF is well-formed).
set -u
exe="$NC_BIN/dem_solver"
out="$NC_TMP/signal"
"$exe" "$NC_ROOT/dem_solver/examples/settle.json" --output "$out" >"$NC_TMP/signal.log" 2>&1 &
pid=$!
for _ in $(seq 1 100); do [ -f "$out/particles.xdmf" ] && break; sleep 0.1; done
sleep 0.5
kill -TERM "$pid"
wait "$pid"
rc=$?
if [ "$rc" -ne 130 ]; then echo "expected exit 130 after SIGTERM, got $rc"; cat "$NC_TMP/signal.log"; exit 1; fi
grep -q "interrupted" "$NC_TMP/signal.log" || { echo "no interruption message"; exit 1; }
"$PYTHON" - "$out" <<'PY' || exit 1
import sys, h5py, xml.etree.ElementTree as ET
out = sys.argv[1]
with h5py.File(out + "/dem.h5", "r") as f:
    n = len(f["time"])
    assert n >= 1, "no output step"
    assert f["particles/position"].shape[0] == n, f["particles/position"].shape
ET.parse(out + "/particles.xdmf")
print("readable after SIGTERM:", n, "output steps")
PY

# Coupled mode: SIGTERM while waiting for the coupler -> exit 130; no coupler at all -> the idle
# timeout ends the run with exit 1 and a message naming the endpoint.
"$exe" "$NC_ROOT/dem_solver/examples/coupled_rock.json" --output "$NC_TMP/c1" \
  --endpoint 'tcp://127.0.0.1:*' --endpoint-file "$NC_TMP/c1.ep" >"$NC_TMP/c1.log" 2>&1 &
pid=$!
for _ in $(seq 1 100); do [ -s "$NC_TMP/c1.ep" ] && break; sleep 0.1; done
grep -q '^tcp://127.0.0.1:[0-9]' "$NC_TMP/c1.ep" || { echo "no endpoint file"; cat "$NC_TMP/c1.log"; exit 1; }
kill -TERM "$pid"
wait "$pid"
rc=$?
[ "$rc" -eq 130 ] || { echo "coupled: expected exit 130 after SIGTERM, got $rc"; cat "$NC_TMP/c1.log"; exit 1; }
"$exe" "$NC_ROOT/dem_solver/examples/coupled_rock.json" --output "$NC_TMP/c2" \
  --endpoint 'tcp://127.0.0.1:*' --idle-timeout 1 >"$NC_TMP/c2.log" 2>&1
rc=$?
[ "$rc" -eq 1 ] && grep -q "idle timeout" "$NC_TMP/c2.log" || {
  echo "idle timeout: expected exit 1 with a message, got $rc"; cat "$NC_TMP/c2.log"; exit 1; }
echo "coupled: SIGTERM -> 130, idle timeout -> 1"
