#!/bin/bash
# Device call 7 (carry .fcl-debs and .gpu-data; 600 s): the final tree (call 6's defaults: the
# scan first on the side stream of the greatest priority, the cells' pairs for every self query
# while the overlap is on). Builds the CUDA tests and runs ctest -L cuda; then compute-sanitizer
# memcheck and racecheck of the cells' test (float: the cells' kernel beside the scan, and one
# after the other).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c7
mkdir -p $W
OUT=$W CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  timeout 480 scripts/gpu_check.sh > $W/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -30 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
for tool in memcheck racecheck; do
  left=$((585 - ($(date +%s) - START)))
  if [ $left -lt 20 ]; then echo "$tool skipped (time)" >> $T; continue; fi
  timeout $((left - 5)) $SAN --tool $tool --error-exitcode 3 build-gpu/tests/test_cuda_query \
    --gtest_filter='CudaQueryTyped/0.SelfPairsWithinALevel*' > $W/$tool.log 2>&1
  echo "$tool rc=$?" >> $T; tail -2 $W/$tool.log >> $T
done
tar czf $OUT/logs.tgz -C $W check.log ctest.log $(cd $W && ls build.log memcheck.log racecheck.log 2>/dev/null)
date >> $T
