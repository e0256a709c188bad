#!/usr/bin/env bash
# Exits 0 when every package netcouple needs is installed, 1 (listing the missing ones) otherwise.
#   scripts/check_deps.sh [--bench]   (--bench: also what `make bench` needs)
set -u
here=$(cd "$(dirname "$0")" && pwd)
missing=()
while read -r p; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done < <("$here/install_deps.sh" --list "$@")
if [ ${#missing[@]} -gt 0 ]; then
  echo "check_deps: missing packages: ${missing[*]}" >&2
  exit 1
fi
exit 0
