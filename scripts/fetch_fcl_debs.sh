#!/usr/bin/env bash
# Downloads the Debian packages of FCL (and its CMake dependencies ccd and octomap) into
# ${FCL_DEBS_DIR:-.fcl-debs}/ and unpacks each into ${FCL_DEBS_DIR}/root, without installing
# anything. Run it on a machine with network access and apt (any user; no root needed when the
# apt lists exist), then copy the folder to an offline GPU machine and run scripts/gpu_check.sh.
#
# Besides FCL it fetches the project's other build dependencies that a bare CUDA machine tends
# to lack (tinyobjloader, GMP's headers); override with FCL_DEBS_EXTRA="" to fetch FCL alone.
# libgmp10 itself is not fetched: every system has it, and gpu_check.sh points the -dev
# symlinks at the system copy.
#
# Idempotent: packages already downloaded are not fetched again.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

DEBS_DIR="${FCL_DEBS_DIR:-.fcl-debs}"
FCL_PACKAGES=(libfcl-dev libfcl0.7 libccd-dev libccd2 liboctomap-dev liboctomap1.9)
# shellcheck disable=SC2206
EXTRA=(${FCL_DEBS_EXTRA-libtinyobjloader-dev libtinyobjloader2rc10 libgmp-dev libgmpxx4ldbl})
PACKAGES=("${FCL_PACKAGES[@]}" ${EXTRA[@]+"${EXTRA[@]}"})

log() { printf '[fetch_fcl_debs] %s\n' "$*"; }

command -v apt-get >/dev/null || { echo "apt-get not found: run this on Debian/Ubuntu" >&2; exit 1; }
command -v dpkg-deb >/dev/null || { echo "dpkg-deb not found" >&2; exit 1; }

mkdir -p "$DEBS_DIR"
cd "$DEBS_DIR"

todo=()
for pkg in "${PACKAGES[@]}"; do
  compgen -G "${pkg}_*.deb" >/dev/null || todo+=("$pkg")
done

if ((${#todo[@]})); then
  log "downloading: ${todo[*]}"
  if ! apt-get download "${todo[@]}"; then
    if [[ "$(id -u)" -eq 0 ]]; then
      log "apt-get download failed; refreshing the package lists and retrying"
      apt-get update
      apt-get download "${todo[@]}"
    else
      echo "[fetch_fcl_debs] apt-get download failed; try 'sudo apt-get update' first" >&2
      exit 1
    fi
  fi
else
  log "all packages already downloaded"
fi

# Unpack afresh so that a removed or replaced .deb leaves nothing stale behind.
rm -rf root
mkdir -p root
for deb in ./*.deb; do
  log "unpacking ${deb#./}"
  dpkg-deb -x "$deb" root
done

log "done: $(pwd)/root"
log "configure with: -DCMAKE_PREFIX_PATH=$(pwd)/root/usr" \
    "-Dccd_DIR=$(pwd)/root/usr/lib/x86_64-linux-gnu/ccd" \
    "-Doctomap_DIR=$(pwd)/root/usr/share/octomap"
