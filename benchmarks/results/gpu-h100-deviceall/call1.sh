#!/bin/bash
# First device call of branch device-all (written without a device; carry .fcl-debs and
# .gpu-data; give it 600 s): intersectAllOnDevice. Builds every CUDA test and gpu_bench, runs
# ctest -L cuda, memcheck of the two device-output tests, then gpu_bench on the UNC scenes (the
# two-frame scenes run joint: kdet_device_ms is their first pairs-on-device time) and the 90k and
# 1M cloths, two rounds. Files go straight to $OUT as they are made.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/chk/ctest.log | head -30 >> $T
cp /tmp/chk/ctest.log $OUT/ctest.log 2>/dev/null
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 120 $SAN --tool memcheck build-gpu/tests/test_cuda_query --gtest_filter='CudaQueryTyped/0.*OnTheDevice*' > $OUT/memcheck.log 2>&1
echo "memcheck rc=$?" >> $T; tail -2 $OUT/memcheck.log >> $T
date >> $T
for r in 1 2; do
  timeout 120 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 --only unc --only cloth-90k --only cloth-1000k \
    --csv $OUT/bench-$r.csv > $OUT/bench-$r.log 2>&1
  echo "bench round $r rc=$?" >> $T
done
date >> $T
