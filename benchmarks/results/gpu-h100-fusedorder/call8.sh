#!/bin/bash
# Device call 8 (carry .fcl-debs and .gpu-data): the pass's counters written by the order's one
# launch into mapped page-locked memory in one trip, instead of a copy after it
# (KDET_FCL_CUDA_MAPPED_COUNTERS, default on; probe: trip_probe.cu, call 7). Builds the CUDA tests
# and gpu_bench; ctest -L cuda; memcheck and racecheck of the counting-order and one-trip tests
# (float); gpu_bench (GPU only) on the UNC scenes and the 20k, 90k, 250k and 1M cloths in eight
# rounds alternating the knob (1, 0, ...).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/c8
OUT=/tmp/c8 CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  scripts/gpu_check.sh > /tmp/c8/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/c8/ctest.log | head -30 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
F='CudaQueryTyped/0.OneTripBrings*:CudaQueryTyped/0.PairsAreOrderedByCounting*'
for tool in memcheck racecheck; do
  timeout 240 $SAN --tool $tool --error-exitcode 3 build-gpu/tests/test_cuda_query \
    --gtest_filter="$F" > /tmp/c8/$tool-new.log 2>&1
  echo "$tool ($F) rc=$?" >> $T; tail -2 /tmp/c8/$tool-new.log >> $T
done
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for R in 1 0 1 0 1 0 1 0; do
  r=$((r + 1))
  KDET_FCL_CUDA_MAPPED_COUNTERS=$R timeout 100 $B --no-fcl --no-cpu --repeats 20 \
    --only unc --only cloth-20k --only cloth-90k --only cloth-250k --only cloth-1000k \
    --csv /tmp/c8/bench-$r.csv >> /tmp/c8/bench.log 2>&1
  echo "bench round $r (mapped counters $R) rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/c8/bench-1.csv | sed 's/^/round,fused,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/c8/bench-$r.csv | sed "s/^/$r,$R,/" >> $OUT/bench.csv
done
date >> $T
tar czf $OUT/logs.tgz -C /tmp/c8 check.log ctest.log bench.log memcheck-new.log racecheck-new.log \
  $(cd /tmp/c8 && ls build.log 2>/dev/null)
date >> $T
