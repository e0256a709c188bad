#!/usr/bin/env bash
# Installs the Debian packages netcouple needs, only those that are missing.
# Run as root (or through sudo). `make test`, `make demo` and `make all` call it on their own
# when `scripts/check_deps.sh` finds something missing.
#   scripts/install_deps.sh            install what is missing
#   scripts/install_deps.sh --bench    the same plus what only `make bench` needs
#   scripts/install_deps.sh --list [--bench]   print the package list and exit
set -euo pipefail

# build: compilers, pkg-config; libraries: ZeroMQ, HDF5, cJSON, SuiteSparse, cmocka (unit tests),
# OpenBLAS (CHOLMOD's dense kernels: several times faster than the reference BLAS);
# clang + its runtime for the libFuzzer target; python packages for plots, the Python
# participant and the end-to-end checks; hdf5-tools for h5dump/h5ls.
PACKAGES=(
  build-essential pkg-config
  libzmq3-dev libhdf5-dev libcjson-dev libsuitesparse-dev libcmocka-dev
  liblapack-dev libopenblas0-pthread
  clang libclang-rt-dev
  hdf5-tools
  python3 python3-zmq python3-h5py python3-numpy python3-matplotlib
)

# only for `make bench`: LIGGGHTS and CalculiX, the reference DEM and FEM codes the
# benchmarks compare with
BENCH_PACKAGES=(liggghts calculix-ccx)

list=0
for arg in "$@"; do
  case "$arg" in
    --list) list=1 ;;
    --bench) PACKAGES+=("${BENCH_PACKAGES[@]}") ;;
    *) echo "install_deps: unknown option $arg" >&2; exit 2 ;;
  esac
done
if [ $list -eq 1 ]; then
  printf '%s\n' "${PACKAGES[@]}"
  exit 0
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all packages present"
  exit 0
fi

echo "install_deps: missing: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then
    SUDO="sudo"
  else
    echo "install_deps: not root and no sudo; install these packages: ${missing[*]}" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "install_deps: done"
