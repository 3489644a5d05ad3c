#!/usr/bin/env bash
# Builds the whole test suite with AddressSanitizer + UndefinedBehaviorSanitizer into
# ${ASAN_BUILD_DIR:-build-asan} (CPU only, no benchmarks, no Python module) and runs it with
# ctest. Any sanitizer report aborts the test that triggered it (-fno-sanitize-recover=all), so
# it fails.
# Extra arguments go to ctest. Ends with ctest's summary; the exit status is ctest's.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
BUILD="${ASAN_BUILD_DIR:-build-asan}"
JOBS="${JOBS:-$(nproc 2>/dev/null || echo 2)}"
# RelWithDebInfo would add -O2 -g: -O1 with line tables (-g1) is all the reports need, and it
# compiles faster.
opt="-O1 -g1 -DNDEBUG"
flags="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all"
echo "[sanitize] configuring $BUILD"
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$opt" -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DKDET_FCL_CUDA=OFF -DKDET_FCL_BUILD_BENCHMARKS=OFF -DKDET_FCL_PYTHON=OFF >/dev/null
echo "[sanitize] building $BUILD with $JOBS jobs"
cmake --build "$BUILD" --parallel "$JOBS" >/dev/null
# Two reports come from FCL itself, not from kdet_fcl, and are silenced narrowly:
#  - alloc_dealloc_mismatch=0: libfcl.so (not instrumented) allocates a BVHModel's arrays through
#    Eigen's aligned operator new, and the destructor instantiated from FCL's headers in our
#    instrumented code frees them with operator delete[]; ASan sees "malloc vs delete[]".
#  - scripts/lsan-fcl.supp: FCL's BVHModel::beginModel leaks when a model is rebuilt.
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1:alloc_dealloc_mismatch=0}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$ROOT/scripts/lsan-fcl.supp:print_suppressions=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
# The install test re-configures a consumer without the sanitizer flags: it checks packaging,
# which the regular build already covers, so it is left out here.
exec ctest --test-dir "$BUILD" --output-on-failure -j2 -LE install "$@"
