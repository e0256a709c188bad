#!/usr/bin/env bash
# A participant that takes 4 s to start (a large model, a slow machine), then is the Python
# ball DEM with the solvers' arguments: CONFIG --endpoint EP --output DIR --endpoint-file FILE
# Stopped while it waits, it stops its pause too (nothing of it outlives it).
here=$(cd "$(dirname "$0")" && pwd)
trap 'kill "$pause" 2>/dev/null; wait "$pause" 2>/dev/null; exit 143' TERM INT
sleep 4 & pause=$!
wait "$pause"
exec "${PYTHON:-/usr/bin/python3}" "$here/../../../scripts/participants/ball_dem.py" "$@"
