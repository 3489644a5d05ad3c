#!/bin/bash
# Device call 6 (carry .fcl-debs and .gpu-data; 600 s): the final tree (call 5's spread taken
# back: the same CUDA code as call 4's). Builds the CUDA tests and runs ctest -L cuda; then
# compute-sanitizer memcheck of the coplanar-pairs test (the exact test's 2D branch on the device).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c6
mkdir -p $W
OUT=$W CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  timeout 520 scripts/gpu_check.sh > $W/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -30 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
left=$((585 - ($(date +%s) - START)))
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
if [ $left -gt 20 ]; then
  timeout $((left - 5)) $SAN --tool memcheck --error-exitcode 3 build-gpu/tests/test_cuda_query \
    --gtest_filter='CudaQuery.CoplanarPairs*' > $W/memcheck.log 2>&1
  echo "memcheck rc=$?" >> $T; tail -2 $W/memcheck.log >> $T
fi
tar czf $OUT/logs.tgz -C $W check.log ctest.log $(cd $W && ls build.log memcheck.log 2>/dev/null)
date >> $T
