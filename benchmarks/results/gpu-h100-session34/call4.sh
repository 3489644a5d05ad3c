#!/bin/bash
# Device call 4 (carry .fcl-debs and .gpu-data; 600 s): the committed change. Runs
# scripts/gpu_check.sh: ctest -L cuda (with the new test_cuda_predicates) and precision_bench on
# the CPU and the GPU (PRECISION_BENCH=1, --repeats 7 --no-plot, as the GPU section of
# RESULTS-precision.md).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
W=$OUT/gc
OUT=$W CTEST_ALL=0 JOBS=16 PRECISION_BENCH=1 PRECISION_BENCH_ARGS="--repeats 7 --no-plot" \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh test_cuda_warp_search test_cuda_predicates gpu_bench precision_bench" \
  timeout 560 scripts/gpu_check.sh > $OUT/gpu_check.log 2>&1
echo "gpu_check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -20 >> $T
gzip $W/ctest.log $W/build.log
date >> $T
