#!/bin/bash
# Device call 6 (carry .fcl-debs and .gpu-data; 600 s): the final tree (8bfd171: the packed
# candidates, the mended tests, the split read-back taken back). Runs scripts/gpu_check.sh:
# every CUDA test program built, ctest -L cuda.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=$OUT/gc
OUT=$W CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh test_cuda_warp_search test_cuda_predicates" \
  timeout 560 scripts/gpu_check.sh > $OUT/gpu_check.log 2>&1
echo "gpu_check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -20 >> $T
gzip $W/ctest.log $W/build.log
date >> $T
