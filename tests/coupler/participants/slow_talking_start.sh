#!/usr/bin/env bash
# A participant that takes 4 s to start and says so once a second on its output (as
# fem_solver reports a long initial equilibrium), then is the Python ball DEM with the
# solvers' arguments: CONFIG --endpoint EP --output DIR --endpoint-file FILE
# Stopped while it waits, it stops its pause too (nothing of it outlives it).
here=$(cd "$(dirname "$0")" && pwd)
trap 'kill "$pause" 2>/dev/null; wait "$pause" 2>/dev/null; exit 143' TERM INT
for k in 1 2 3 4; do
  echo "slow_talking_start: still starting ($k s)"
  sleep 1 & pause=$!
  wait "$pause"
done
exec "${PYTHON:-/usr/bin/python3}" "$here/../../../scripts/participants/ball_dem.py" "$@"
