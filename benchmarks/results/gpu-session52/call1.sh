#!/usr/bin/env bash
# Session 52, call 1: libkdet_fcl_interpose.so on a GPU machine (FCL from .fcl-debs, offline).
# Builds the library with CUDA, the interposer and the unmodified FCL program; runs the
# interpose tests (the cuda case takes the GPU); then benchmarks/interpose_bench.sh with the
# CPU backend (16 threads) and with KDET_FCL_INTERPOSE_BACKEND=cuda. With TRUST_RUN=1 (call 3)
# also with the CPU backend and KDET_FCL_INTERPOSE_CACHE=trust, and the log is $OUT/$NAME.txt.
set -uo pipefail
OUT="${OUT:-gpu-logs}"; mkdir -p "$OUT"
ROOT="$PWD"
DEBS="$ROOT/.fcl-debs/root"; LIB="$DEBS/usr/lib/x86_64-linux-gnu"
export LD_LIBRARY_PATH="$LIB${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
{
  nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv
  echo "host threads: $(nproc)"
  cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=$DEBS/usr" \
    "-Dccd_DIR=$LIB/ccd" "-Doctomap_DIR=$DEBS/usr/share/octomap" -DKDET_FCL_CUDA=ON \
    -DCMAKE_CUDA_ARCHITECTURES=90 -DKDET_FCL_CUDA_ARCHITECTURES=90 \
    -DCMAKE_POLICY_VERSION_MINIMUM=3.5 -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc \
    -DKDET_FCL_BUILD_BENCHMARKS=OFF >/dev/null &&
  cmake --build build-gpu -j"$(nproc)" --target kdet kdet_fcl_interpose example_unmodified_fcl >/dev/null &&
  echo "build OK"
  ./build-gpu/kdet info
  ctest --test-dir build-gpu -R interpose --output-on-failure
  for c in cpu cuda; do echo "== interpose_$c stderr"; cat build-gpu/interpose_$c/*.err 2>/dev/null | grep -v "^$" | head -20; done
  echo "== bench, CPU backend"
  benchmarks/interpose_bench.sh build-gpu 3 15
  if [[ "${TRUST_RUN:-0}" == 1 ]]; then
    echo "== bench, CPU backend, cache trust"
    KDET_FCL_INTERPOSE_CACHE=trust benchmarks/interpose_bench.sh build-gpu 3 15
  fi
  echo "== bench, CUDA backend"
  KDET_FCL_INTERPOSE_BACKEND=cuda benchmarks/interpose_bench.sh build-gpu 3 15
} >"$OUT/${NAME:-call1}.txt" 2>&1
tail -n 40 "$OUT/${NAME:-call1}.txt"
