#!/usr/bin/env bash
# A participant that publishes an endpoint nobody listens on and dies before the handshake
# (exit 1), as a solver that crashes right after binding would. Takes the solvers' arguments:
#   CONFIG --endpoint EP --output DIR --endpoint-file FILE
file=""
while [ $# -gt 0 ]; do
  case "$1" in --endpoint-file) file=$2; shift 2 ;; *) shift ;; esac
done
[ -n "$file" ] || { echo "dies_after_endpoint: no --endpoint-file" >&2; exit 2; }
echo "tcp://127.0.0.1:9" > "$file.tmp" && mv "$file.tmp" "$file"
# die once the coupler is connecting: after the other participant's endpoint is out too
for _ in $(seq 200); do [ "$(ls "$(dirname "$file")"/*.endpoint | wc -l)" -ge 2 ] && break; sleep 0.05; done
sleep 0.3
echo "dies_after_endpoint: exiting before the handshake, as asked" >&2
exit 1
