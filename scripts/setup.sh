#!/usr/bin/env bash
# Installs the missing build dependencies (Debian/Ubuntu, apt-get) and configures + builds
# kdet_fcl (Release) into ${BUILD_DIR:-build}. Idempotent: a second run installs nothing and
# only rebuilds what changed.
#
# Environment:
#   BUILD_DIR   build directory (default: build, relative to the repository root)
#   CMAKE_ARGS  extra arguments for the cmake configure step (word-split), e.g.
#               CMAKE_ARGS="-DKDET_FCL_CUDA=OFF -DKDET_FCL_BUILD_BENCHMARKS=OFF"
#   JOBS        parallel build jobs (default: nproc)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

BUILD_DIR="${BUILD_DIR:-build}"
CMAKE_ARGS="${CMAKE_ARGS:-}"
JOBS="${JOBS:-$(nproc 2>/dev/null || echo 2)}"

# libgmp-dev: the exact-arithmetic referee in the tests; gnuplot-nox: plots in the benchmarks;
# clang + libclang-rt-14-dev: libFuzzer for scripts/fuzz.sh (CI runs it after the tests);
# python3-dev + pybind11-dev + python3-numpy: the Python module (python/, for /usr/bin/python3).
PACKAGES=(build-essential cmake libgtest-dev libbenchmark-dev libeigen3-dev libccd-dev
          libfcl-dev libtinyobjloader-dev libgmp-dev gnuplot-nox clang libclang-rt-14-dev
          python3-dev pybind11-dev python3-numpy)

log() { printf '[setup] %s\n' "$*"; }

# ---- 1. packages: install only what is missing --------------------------------------------
installed() {
  dpkg -s "$1" 2>/dev/null | grep -q '^Status: install ok installed'
}

missing=()
if command -v dpkg >/dev/null 2>&1; then
  for pkg in "${PACKAGES[@]}"; do
    installed "$pkg" || missing+=("$pkg")
  done
else
  log "dpkg not found (not Debian/Ubuntu): skipping the package check"
fi

if ((${#missing[@]})); then
  if [[ "$(id -u)" -ne 0 ]]; then
    echo "[setup] missing packages: ${missing[*]}" >&2
    echo "[setup] install them as root, then run this script again:" >&2
    echo "    sudo apt-get update && sudo apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
  log "installing: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update
  apt-get install -y --no-install-recommends "${missing[@]}"
else
  log "all packages present"
fi

# ---- 2. configure and build ---------------------------------------------------------------
cmake_args=(-S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release)
if [[ -x /usr/local/cuda/bin/nvcc ]]; then
  # The CMake probes this path too; naming it keeps a PATH without CUDA from mattering.
  cmake_args+=(-DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc)
fi
# shellcheck disable=SC2206  # CMAKE_ARGS is deliberately word-split
extra=(${CMAKE_ARGS})

log "configuring $BUILD_DIR"
cmake "${cmake_args[@]}" ${extra[@]+"${extra[@]}"}

log "building $BUILD_DIR with $JOBS jobs"
cmake --build "$BUILD_DIR" --parallel "$JOBS"
log "done"
