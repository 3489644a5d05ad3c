#!/bin/bash
# Device call 2 (carry .fcl-debs and .gpu-data): results kept across frames (intersectSelf/
# intersectMeshes/intersectAll into a result; pooled read-back). Builds every CUDA test program
# and gpu_bench; ctest -L cuda; memcheck of the new tests; gpu_bench on the UNC scenes and the
# 90k and 1M cloths in four rounds alternating kept results (default) and --fresh-results.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/chk/ctest.log | head -30 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 150 $SAN --tool memcheck --error-exitcode 3 build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQueryTyped/0.ResultsKept*' > /tmp/chk/memcheck-new.log 2>&1
echo "memcheck (kept results) rc=$?" >> $T; tail -2 /tmp/chk/memcheck-new.log >> $T
timeout 150 $SAN --tool memcheck --error-exitcode 3 build-gpu/tests/test_cuda_upload \
  --gtest_filter='*Pool*' > /tmp/chk/memcheck-upload.log 2>&1
echo "memcheck (pooled download) rc=$?" >> $T; tail -2 /tmp/chk/memcheck-upload.log >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for M in kept fresh kept fresh; do
  r=$((r + 1))
  A=""; [ $M = fresh ] && A="--fresh-results"
  timeout 100 $B --no-fcl --no-cpu --repeats 20 $A \
    --only unc --only cloth-90k --only cloth-1000k \
    --csv /tmp/chk/bench-$r.csv >> /tmp/chk/bench.log 2>&1
  echo "bench round $r ($M) rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/chk/bench-1.csv | sed 's/^/round,results,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/chk/bench-$r.csv | sed "s/^/$r,$M,/" >> $OUT/bench.csv
done
date >> $T
tar czf $OUT/logs.tgz -C /tmp/chk check.log ctest.log bench.log memcheck-new.log memcheck-upload.log \
  $(cd /tmp/chk && ls build.log 2>/dev/null)
date >> $T
