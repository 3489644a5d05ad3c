#!/usr/bin/env bash
# Builds kdet_fcl with CUDA on an offline machine with an NVIDIA GPU but without FCL, and runs
# the CUDA tests and then the whole suite. Needs no network.
#
#   scripts/gpu_check.sh [DEBS_ROOT]
#
# DEBS_ROOT (default: .fcl-debs/root) is a folder of unpacked Debian packages made by
# scripts/fetch_fcl_debs.sh on a machine with network access (copy .fcl-debs/ along).
#
# Environment:
#   OUT         where the logs go (default: gpu-logs): nvidia-smi.txt, build.log, ctest.log
#   BUILD_DIR   build directory (default: build-gpu)
#   CMAKE_ARGS  extra configure arguments (word-split)
#   JOBS        parallel build/test jobs (default: nproc)
#   KDET_FCL_DATA_DIR  test/benchmark data (default: .gpu-data when it exists: a copy of the
#               needed ../shared/data files, since an offline GPU machine has no ../shared)
#   GPU_BENCH   1: also run the GPU benchmark (benchmarks/gpu_bench; log and CSV in OUT)
#   TARGETS     build only these targets (space-separated; default: everything). ctest -L cuda
#               also runs cli_backend (the kdet tool's --backend cuda), interpose_cuda (an
#               unmodified FCL program on the GPU) and python_cuda (the Python module, built
#               where python3 has pybind11 and NumPy), so their targets are added to them
#   CTEST_ALL   0: skip the run of the whole suite after the CUDA label (default 1)
#   SANITIZER   1: also run compute-sanitizer memcheck and racecheck on small CUDA test scenes
#               (queries, an overflow, 128-bit keys, both scans, the commit's and update's copies,
#               the counting build's grouped cells, a scan past a cell it skips whole, a
#               mesh that outgrows its hash, a re-hash graph whose buffers moved)
#   SANITIZER_TOOLS  the compute-sanitizer tools SANITIZER=1 runs (default: "memcheck racecheck";
#               racecheck takes minutes, so a time-limited session may run each in its own call)
#   PRECISION_BENCH  1: also run benchmarks/precision_bench (the speed/accuracy trade of the
#               predicate modes on the CPU and the GPU; outputs in OUT/precision)
# Exit status: 0 when the build and both test runs pass, else non-zero.
set -uo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

DEBS_ROOT="${1:-${FCL_DEBS_ROOT:-.fcl-debs/root}}"
OUT="${OUT:-gpu-logs}"
BUILD_DIR="${BUILD_DIR:-build-gpu}"
CMAKE_ARGS="${CMAKE_ARGS:-}"
JOBS="${JOBS:-$(nproc 2>/dev/null || echo 4)}"
ARCH_TRIPLET="x86_64-linux-gnu"

log() { printf '[gpu_check] %s\n' "$*"; }
die() { printf '[gpu_check] error: %s\n' "$*" >&2; exit 1; }

[[ -d "$DEBS_ROOT/usr" ]] ||
  die "no unpacked packages at $DEBS_ROOT (run scripts/fetch_fcl_debs.sh on a machine with network and copy .fcl-debs/ here)"
DEBS_ROOT="$(cd "$DEBS_ROOT" && pwd)"
LIBDIR="$DEBS_ROOT/usr/lib/$ARCH_TRIPLET"
[[ -f "$LIBDIR/cmake/fcl/fcl-config.cmake" ]] || die "$LIBDIR/cmake/fcl/fcl-config.cmake is missing"

mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"

# ---- the machine ---------------------------------------------------------------------------
{
  date -u '+%Y-%m-%dT%H:%M:%SZ'
  uname -a
  if command -v nvidia-smi >/dev/null 2>&1; then
    nvidia-smi
    nvidia-smi --query-gpu=index,name,compute_cap,memory.total,driver_version --format=csv
  else
    echo "nvidia-smi: not found"
  fi
  if [[ -x /usr/local/cuda/bin/nvcc ]]; then /usr/local/cuda/bin/nvcc --version; fi
  cmake --version | head -n 1
} >"$OUT/nvidia-smi.txt" 2>&1
log "machine description: $OUT/nvidia-smi.txt"

# ---- point the unpacked -dev symlinks whose library was not fetched (libgmp.so -> the
#      system's libgmp.so.10) at the system's copy --------------------------------------------
while IFS= read -r -d '' link; do
  target="$(basename "$(readlink "$link")")"
  soname="$(sed -E 's/(\.so\.[0-9]+).*/\1/' <<<"$target")"
  for dir in "/usr/lib/$ARCH_TRIPLET" "/lib/$ARCH_TRIPLET" /usr/lib64 /usr/lib; do
    if [[ -e "$dir/$soname" ]]; then
      ln -sfn "$dir/$soname" "$link"
      log "$(basename "$link") -> $dir/$soname (system copy)"
      break
    fi
  done
done < <(find "$LIBDIR" -maxdepth 1 -xtype l -print0)

export LD_LIBRARY_PATH="$LIBDIR${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
if [[ -z "${KDET_FCL_DATA_DIR:-}" && -d "$ROOT/.gpu-data" ]]; then
  export KDET_FCL_DATA_DIR="$ROOT/.gpu-data"
fi

# ---- configure and build -------------------------------------------------------------------
cmake_args=(
  -S "$ROOT" -B "$BUILD_DIR"
  -DCMAKE_BUILD_TYPE=Release
  "-DCMAKE_PREFIX_PATH=$DEBS_ROOT/usr"
  "-Dccd_DIR=$LIBDIR/ccd"
  "-Doctomap_DIR=$DEBS_ROOT/usr/share/octomap"
  -DKDET_FCL_CUDA=ON
  -DCMAKE_CUDA_ARCHITECTURES=90
  -DKDET_FCL_CUDA_ARCHITECTURES=90
  # The packaged config files are from CMake 3.x; let a CMake 4 read them.
  -DCMAKE_POLICY_VERSION_MINIMUM=3.5
  # Multiarch headers of the unpacked packages (gmp.h lives in include/<triplet>).
  "-DCMAKE_CXX_FLAGS=-isystem $DEBS_ROOT/usr/include/$ARCH_TRIPLET"
  # ... and their libraries for targets that link them by plain name (gmp, gmpxx).
  "-DCMAKE_EXE_LINKER_FLAGS=-L$LIBDIR"
)
[[ -x /usr/local/cuda/bin/nvcc ]] && cmake_args+=(-DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc)
# The Python module for the python3 on PATH where it has pybind11 and NumPy (pip's pybind11 names
# its CMake folder); otherwise it is left out.
if python3 -c "import pybind11, numpy" >/dev/null 2>&1; then
  cmake_args+=("-DPython_EXECUTABLE=$(command -v python3)"
               "-Dpybind11_DIR=$(python3 -m pybind11 --cmakedir)" -DKDET_FCL_PYTHON=ON)
  # The Python tests preload the compiler's libstdc++ (python/CMakeLists.txt,
  # KDET_FCL_PYTHON_TEST_PRELOAD): a toolchain that copies parts of libstdc++ into the shared
  # library (as the GPU image's /opt/gcc does) leaves a Python process, which has no libstdc++ of
  # its own, with two copies, and formatting a number then crashes. The preload is the library's
  # own libstdc++, so it changes nothing elsewhere.
  cc_cxx=$(readlink -f "$("${CXX:-c++}" -print-file-name=libstdc++.so.6)" 2>/dev/null)
  [[ -f "$cc_cxx" ]] && cmake_args+=("-DKDET_FCL_PYTHON_TEST_PRELOAD=$cc_cxx")
else
  cmake_args+=(-DKDET_FCL_PYTHON=OFF)
fi
# shellcheck disable=SC2206
extra=(${CMAKE_ARGS})

# (ctest -L cuda runs cli_backend, the kdet tool on the GPU, interpose_cuda and python_cuda.)
if [[ -n "${TARGETS:-}" ]]; then
  extra_targets="kdet kdet_fcl_interpose example_unmodified_fcl"
  [[ " ${cmake_args[*]} " == *" -DKDET_FCL_PYTHON=ON "* ]] && extra_targets+=" _kdet_fcl"
  for t in $extra_targets; do
    if [[ " $TARGETS " != *" $t "* ]]; then TARGETS="$TARGETS $t"; fi
  done
fi
log "configuring and building $BUILD_DIR (log: $OUT/build.log)"
{
  echo "LD_LIBRARY_PATH=$LD_LIBRARY_PATH"
  echo "+ cmake ${cmake_args[*]} ${extra[*]:-}"
  cmake "${cmake_args[@]}" ${extra[@]+"${extra[@]}"} &&
    echo "+ cmake --build $BUILD_DIR --parallel $JOBS ${TARGETS:+--target $TARGETS}" &&
    cmake --build "$BUILD_DIR" --parallel "$JOBS" ${TARGETS:+--target $TARGETS}
} >"$OUT/build.log" 2>&1
build_rc=$?
if ((build_rc != 0)); then
  tail -n 40 "$OUT/build.log" >&2
  die "the build failed (exit $build_rc): see $OUT/build.log"
fi
log "build OK"

# ---- tests: the CUDA label first (verbose, to log the device), then everything -------------
: >"$OUT/ctest.log"
log "ctest -L cuda (log: $OUT/ctest.log)"
{
  echo "==== ctest -L cuda"
  ctest --test-dir "$BUILD_DIR" -L cuda -V --output-on-failure
} >>"$OUT/ctest.log" 2>&1
cuda_rc=$?
# Zero tests with the label is a failure too: the CUDA tests were not built.
if grep -q "No tests were found" "$OUT/ctest.log"; then cuda_rc=1; fi
# On a machine where nvidia-smi sees a GPU, a skipped CUDA test means the runtime found none
# (the tests of two devices, CudaDevicesTwoGpus.*, skip on a machine of one where they cannot run).
gpus=0
command -v nvidia-smi >/dev/null 2>&1 && gpus=$(nvidia-smi -L 2>/dev/null | grep -c '^GPU ')
# (ctest's line per test: "N/M Test #K: <name> ...***Skipped")
skipped=$(grep -E '\*\*\*Skipped' "$OUT/ctest.log" | grep -v 'CudaDevicesTwoGpus' || true)
if ((gpus >= 2)); then skipped=$(grep -E '\*\*\*Skipped' "$OUT/ctest.log" || true); fi
if ((gpus >= 1)) && [[ -n "$skipped" ]]; then
  log "nvidia-smi lists $gpus GPU(s) but CUDA tests were skipped:"
  printf '%s\n' "$skipped" >&2
  cuda_rc=1
fi
log "ctest -L cuda: exit $cuda_rc"

all_rc=0
if [[ "${CTEST_ALL:-1}" != 0 ]]; then
  log "ctest (all) (log: $OUT/ctest.log)"
  {
    echo
    echo "==== ctest (all)"
    ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$JOBS"
  } >>"$OUT/ctest.log" 2>&1
  all_rc=$?
  log "ctest (all): exit $all_rc"
fi
grep -E "tests passed|tests failed|The following tests" "$OUT/ctest.log" || true

# ---- optional: compute-sanitizer on a small scene, and the GPU benchmark --------------------
san_rc=0
if [[ "${SANITIZER:-0}" == 1 ]]; then
  SAN="$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)"
  # (with the copies of commitVertices and updateVertices beside the queries' kernels)
  filter='CudaQueryTyped/*.ClothOverSphereAndSelf:CudaQuery.OutputOverflowGrowsAndReruns:CudaQuery.HugeSizeRatioUsesFull128BitKeys:CudaQuery.WarpAndTileScansFindTheSameCandidatesAndPairs:CudaQuery.ACommitCopies*:CudaQuery.UpdateVerticesCopies*:CudaQueryTyped/0.CountingBuildsGroup*:CudaQueryTyped/0.AWarpScanLooksOnPast*:CudaQueryTyped/0.ANewMeshAtAFreed*:CudaQuery.AMeshThatOutgrows*:CudaQuery.ARehashGraphWhoseBuffersMoved*'
  for tool in ${SANITIZER_TOOLS:-memcheck racecheck}; do
    log "compute-sanitizer --tool $tool (log: $OUT/sanitizer-$tool.log)"
    "$SAN" --tool "$tool" --error-exitcode 3 "$BUILD_DIR/tests/test_cuda_query" \
      --gtest_filter="$filter" >"$OUT/sanitizer-$tool.log" 2>&1 || san_rc=1
    tail -n 3 "$OUT/sanitizer-$tool.log"
  done
fi
bench_rc=0
if [[ "${GPU_BENCH:-0}" == 1 ]]; then
  log "gpu_bench (log: $OUT/gpu_bench.log)"
  "$BUILD_DIR/benchmarks/gpu_bench" ${GPU_BENCH_ARGS:-} --csv "$OUT/gpu_bench.csv" \
    >"$OUT/gpu_bench.log" 2>&1 || bench_rc=1
  cat "$OUT/gpu_bench.log"
fi

if [[ "${PRECISION_BENCH:-0}" == 1 ]]; then
  log "precision_bench (log: $OUT/precision_bench.log)"
  "$BUILD_DIR/benchmarks/precision_bench" ${PRECISION_BENCH_ARGS:-} --out "$OUT/precision" \
    >"$OUT/precision_bench.log" 2>&1 || bench_rc=1
  tail -n 30 "$OUT/precision_bench.log"
fi

if ((cuda_rc != 0 || all_rc != 0 || san_rc != 0 || bench_rc != 0)); then
  log "FAILED (see $OUT/ctest.log)"
  exit 1
fi
log "all OK"
