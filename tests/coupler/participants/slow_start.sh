#!/usr/bin/env bash
# A participant that takes 4 s to start (a large model, a slow machine), then is the Python
# ball DEM with the solvers' arguments: CONFIG --endpoint EP --output DIR --endpoint-file FILE
here=$(cd "$(dirname "$0")" && pwd)
sleep 4
exec "${PYTHON:-/usr/bin/python3}" "$here/../../../scripts/participants/ball_dem.py" "$@"
