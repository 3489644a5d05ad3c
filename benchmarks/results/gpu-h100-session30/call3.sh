#!/bin/bash
# Device call 3 (carry .fcl-debs and .gpu-data; 600 s): the final tree (the one trip copies host
# results of up to 4 read-back chunks into the stage, KDET_FCL_CUDA_ONE_TRIP_COPY). Builds the
# CUDA tests and gpu_bench and runs ctest -L cuda; then the full gpu_bench run with every peer in
# one process (--big --repeats 10); then compute-sanitizer memcheck and racecheck of the one-trip
# test (float) as time allows.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c3
mkdir -p $W
OUT=$W CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  timeout 400 scripts/gpu_check.sh > $W/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -30 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
left=$((590 - ($(date +%s) - START)))
timeout $left build-gpu/benchmarks/gpu_bench --big --repeats 10 --csv $OUT/gpu_bench.csv \
  --json $OUT/gpu_bench.json --md $OUT/gpu_bench.md > $W/gpu_bench.log 2>&1
echo "full run rc=$?" >> $T
date >> $T
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
for tool in memcheck racecheck; do
  left=$((585 - ($(date +%s) - START)))
  if [ $left -lt 20 ]; then echo "$tool skipped (time)" >> $T; continue; fi
  timeout $((left - 5)) $SAN --tool $tool --error-exitcode 3 build-gpu/tests/test_cuda_query \
    --gtest_filter='CudaQueryTyped/0.OneTrip*' > $W/$tool.log 2>&1
  echo "$tool rc=$?" >> $T; tail -2 $W/$tool.log >> $T
done
tar czf $OUT/logs.tgz -C $W check.log ctest.log gpu_bench.log $(cd $W && ls build.log memcheck.log racecheck.log 2>/dev/null)
date >> $T
