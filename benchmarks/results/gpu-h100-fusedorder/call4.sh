#!/bin/bash
# Device call 4 (carry .fcl-debs and .gpu-data): the fused order after the counts sized by its pairs
# (at least one block per SM, at most all that fit). Builds test_cuda_query and gpu_bench (cmake as
# scripts/gpu_check.sh, no ctest); runs the counting-order and one-trip tests (float, double);
# gpu_bench (GPU only) on the two cloth-ball frames, the cloth ball, the two n-body frames and the
# 20k cloth in six rounds alternating KDET_FCL_CUDA_FUSED_ORDER (2, 0, 8); then the mutation check:
# each mutation of call4-mutations.diff applied alone, test_cuda_query rebuilt, the two tests run
# (they must fail), the tree restored.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
mkdir -p /tmp/c4
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > /tmp/c4/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_query gpu_bench >> /tmp/c4/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
Q=build-gpu/tests/test_cuda_query
F='CudaQueryTyped/*.OneTripBrings*:CudaQueryTyped/*.PairsAreOrderedByCounting*:CudaQuery.EveryKnob*'
$Q --gtest_filter="$F" > /tmp/c4/tests.log 2>&1
echo "tests rc=$?" >> $T; grep -E "^\[  (PASSED|FAILED) " /tmp/c4/tests.log >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for R in 2 0 8 2 0 8; do
  r=$((r + 1))
  KDET_FCL_CUDA_FUSED_ORDER=$R timeout 100 $B --no-fcl --no-cpu --repeats 20 \
    --only unc-cloth-ball --only unc-n-body-2frames --only cloth-20k \
    --csv /tmp/c4/bench-$r.csv >> /tmp/c4/bench.log 2>&1
  echo "bench round $r (fused order $R) rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/c4/bench-1.csv | sed 's/^/round,fused,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/c4/bench-$r.csv | sed "s/^/$r,$R,/" >> $OUT/bench.csv
done
date >> $T
F2='CudaQueryTyped/0.OneTripBrings*:CudaQueryTyped/0.PairsAreOrderedByCounting*'
for m in 1 2; do
  cp cuda/cuda_backend.cu /tmp/c4/orig.cu
  python3 - "$m" <<'PY'
import sys
m = sys.argv[1]
p = 'cuda/cuda_backend.cu'
s = open(p).read()
subs = {
  '1': ('for (unsigned int b = threadIdx.x; b < blockIdx.x; b += kOrderBlock) before += sums[b];',
        'for (unsigned int b = threadIdx.x; b + 1 < blockIdx.x; b += kOrderBlock) before += sums[b];'),
  '2': ('uint2* const copy = stage != nullptr && z.give <= most ? stage : nullptr;',
        'uint2* const copy = nullptr;'),
}
a, b = subs[m]
assert s.count(a) == 1, m
open(p, 'w').write(s.replace(a, b))
PY
  cmake --build build-gpu --parallel 16 --target test_cuda_query >> /tmp/c4/build-m$m.log 2>&1
  echo "mutation $m build rc=$?" >> $T
  timeout 120 $Q --gtest_filter="$F2" > /tmp/c4/mutation-$m.log 2>&1
  echo "mutation $m tests rc=$? (must be non-zero)" >> $T
  grep -E "^\[  (PASSED|FAILED) |^\[  FAILED  \] Cuda" /tmp/c4/mutation-$m.log | head -5 >> $T
  cp /tmp/c4/orig.cu cuda/cuda_backend.cu
  date >> $T
done
tar czf $OUT/logs.tgz -C /tmp/c4 build.log tests.log bench.log mutation-1.log mutation-2.log
date >> $T
