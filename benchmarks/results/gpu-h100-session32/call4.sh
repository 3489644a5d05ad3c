#!/bin/bash
# Device call 4 (carry .fcl-debs and .gpu-data; 600 s): the final tree's CUDA tests
# (scripts/gpu_check.sh, ctest -L cuda), compute-sanitizer memcheck of the warp search's test,
# and two mutants of warpEntryTriangle compiled with its test alone: (1) no search past the
# window (triangles without entries), (2) the range's end moved also when every probe is at or
# before the warp's first entry.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
W=$OUT/gc
OUT=$W CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh test_cuda_warp_search gpu_bench" \
  timeout 450 scripts/gpu_check.sh > $OUT/gpu_check.log 2>&1
echo "gpu_check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -20 >> $T
date >> $T
CS=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 100 $CS --tool memcheck --error-exitcode 3 build-gpu/tests/test_cuda_warp_search \
  > $OUT/memcheck.log 2>&1
echo "memcheck test_cuda_warp_search rc=$?" >> $T
tail -3 $OUT/memcheck.log >> $T
for m in 1 2; do
  rm -rf /tmp/m$m && mkdir -p /tmp/m$m && cp -r cuda /tmp/m$m/
done
sed -i 's/^  if (__shfl_sync(kFull, start, 31) > e) return lo + static_cast<std::uint32_t>(k);/  return lo + static_cast<std::uint32_t>(k);/' /tmp/m1/cuda/device_hash.cuh
sed -i 's/^    if (m < 32) hi = next;/    hi = next;/' /tmp/m2/cuda/device_hash.cuh
for m in 1 2; do
  diff cuda/device_hash.cuh /tmp/m$m/cuda/device_hash.cuh >> $T
  /usr/local/cuda/bin/nvcc -std=c++17 --generate-code=arch=compute_90,code=sm_90 -fmad=false \
    -I/tmp/m$m -I. -Iinclude tests/test_cuda_warp_search.cu -lgtest -lgtest_main -o /tmp/m$m/t \
    > $OUT/mutant$m.log 2>&1
  timeout 60 /tmp/m$m/t >> $OUT/mutant$m.log 2>&1
  echo "mutant $m rc=$? (expected to fail)" >> $T
  grep -E "^\[  (PASSED|FAILED) |^\[  FAILED|Failure" $OUT/mutant$m.log | head -6 >> $T
done
date >> $T
