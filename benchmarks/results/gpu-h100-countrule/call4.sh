#!/bin/bash
# Device call 4 (carry .fcl-debs and .gpu-data; 600 s): the final tree (the counting build up to
# 300k triangles, the order's loops shared, the exact test's 2D branch for coplanar pairs; the
# exact kernels' spread of call 3 taken back). Builds the CUDA tests and gpu_bench and runs
# ctest -L cuda; then, in the time left, ncu's durations of the exact kernels (clocks unlocked) of
# the 200k cloth and the two n-body frames (call 2 has the 200k cloth's before the 2D branch).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c4
mkdir -p $W
OUT=$W CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  timeout 530 scripts/gpu_check.sh > $W/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -30 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
B=build-gpu/benchmarks/gpu_bench
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in cloth-200k unc-n-body-2frames; do
  left=$((575 - ($(date +%s) - START)))
  if [ $left -lt 25 ]; then echo "ncu $sc skipped (time)" >> $T; continue; fi
  timeout $((left - 5)) $NCU --clock-control none --kernel-name regex:"Exact" \
    --metrics gpu__time_duration.sum,launch__grid_size --csv --print-units base \
    $B --no-fcl --no-cpu --repeats 2 --only $sc > $W/exact-$sc.csv 2> $W/exact-$sc.err
  echo "ncu $sc rc=$?" >> $T
  gzip -c $W/exact-$sc.csv > $OUT/exact-$sc.csv.gz
done
tar czf $OUT/logs.tgz -C $W check.log ctest.log $(cd $W && ls build.log *.err 2>/dev/null)
date >> $T
