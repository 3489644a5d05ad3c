#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, clang with ASan + UBSan) into ${FUZZ_BUILD_DIR:-build-fuzz}
# and runs each one for ${FUZZ_SECONDS:-20} seconds on a scratch copy of its seed corpus
# (fuzz/corpus/<target>/, never modified here). A crash, a sanitizer report, an input slower than
# ${FUZZ_TIMEOUT:-10} s or a leak fails the run; the reproducer is left in ${FUZZ_BUILD_DIR}/artifacts/.
# Installs clang and libclang-rt-14-dev when missing (as root, like scripts/setup.sh).
# Ends with one line: "fuzz: N passed, N failed".
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
BUILD="${FUZZ_BUILD_DIR:-build-fuzz}"
SECONDS_EACH="${FUZZ_SECONDS:-20}"
JOBS="${JOBS:-$(nproc 2>/dev/null || echo 2)}"
TARGETS=(fuzz_read_obj fuzz_read_off fuzz_read_ply fuzz_read_stl fuzz_triangle fuzz_hash)

missing=()
for pkg in clang libclang-rt-14-dev; do
  dpkg -s "$pkg" 2>/dev/null | grep -q '^Status: install ok installed' || missing+=("$pkg")
done
if ((${#missing[@]})); then
  if [[ "$(id -u)" -ne 0 ]]; then
    echo "[fuzz] missing packages: ${missing[*]} (install them as root)" >&2
    exit 1
  fi
  echo "[fuzz] installing: ${missing[*]}"
  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}" >/dev/null
fi

# RelWithDebInfo would add -O2 -g: -O1 with line tables (-g1) is all the reports need, and it
# compiles faster.
opt="-O1 -g1 -DNDEBUG"
flags="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
echo "[fuzz] configuring $BUILD"
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$opt" -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DKDET_FCL_BUILD_FUZZERS=ON -DKDET_FCL_BUILD_TESTS=OFF -DKDET_FCL_BUILD_CLI=OFF \
  -DKDET_FCL_BUILD_BENCHMARKS=OFF -DKDET_FCL_CUDA=OFF -DKDET_FCL_PYTHON=OFF >/dev/null
echo "[fuzz] building ${TARGETS[*]}"
cmake --build "$BUILD" --parallel "$JOBS" --target "${TARGETS[@]}" >/dev/null

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
mkdir -p "$BUILD/artifacts"
passed=0
failed=0
for t in "${TARGETS[@]}"; do
  scratch="$BUILD/corpus-run/$t"
  rm -rf "$scratch" && mkdir -p "$scratch"
  log="$BUILD/artifacts/$t.log"
  if "$BUILD/fuzz/$t" -max_total_time="$SECONDS_EACH" -timeout="${FUZZ_TIMEOUT:-10}" -rss_limit_mb=2048 \
       -max_len=4096 -print_final_stats=1 -artifact_prefix="$BUILD/artifacts/$t-" \
       "$scratch" "fuzz/corpus/$t" >"$log" 2>&1; then
    runs=$(grep -m1 -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')
    echo "[fuzz] $t: ok ($runs inputs in ${SECONDS_EACH}s)"
    passed=$((passed + 1))
  else
    echo "[fuzz] $t: FAILED (log: $log)"
    tail -n 30 "$log" | sed 's/^/    /'
    failed=$((failed + 1))
  fi
done
echo "fuzz: $passed passed, $failed failed"
((failed == 0))
