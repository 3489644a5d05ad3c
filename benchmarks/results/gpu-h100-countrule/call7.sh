#!/bin/bash
# Device call 7 (carry .fcl-debs and .gpu-data; 600 s): a second orient3d filter before the
# expansion (exact::orient3dSumFilter: exact differences, the 24 exact terms summed by Sum2).
# Builds the CUDA tests and gpu_bench; ctest -L cuda; ncu's durations of the exact kernels (clocks
# unlocked) of the 200k cloth, the two n-body frames and the cloth ball (calls 4 and 5 have them
# before the change); gpu_bench (GPU only) on the same scenes and the two cloth-ball frames.
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
  timeout 430 scripts/gpu_check.sh > $W/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -30 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
B=build-gpu/benchmarks/gpu_bench
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in cloth-200k unc-n-body-2frames unc-cloth-ball-self; do
  left=$((540 - ($(date +%s) - START)))
  if [ $left -lt 25 ]; then echo "ncu $sc skipped (time)" >> $T; continue; fi
  timeout $((left < 40 ? left : 40)) $NCU --clock-control none --kernel-name regex:"Exact" \
    --metrics gpu__time_duration.sum,launch__grid_size --csv --print-units base \
    $B --no-fcl --no-cpu --repeats 2 --only $sc > $W/exact-$sc.csv 2> $W/exact-$sc.err
  echo "ncu $sc rc=$?" >> $T
  gzip -c $W/exact-$sc.csv > $OUT/exact-$sc.csv.gz
done
left=$((585 - ($(date +%s) - START)))
if [ $left -gt 20 ]; then
  timeout $((left - 5)) $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --only unc-n-body \
    --only cloth-200k --only cloth-1000k --csv $OUT/bench.csv > $W/bench.log 2>&1
  echo "bench rc=$?" >> $T
fi
tar czf $OUT/logs.tgz -C $W check.log ctest.log $(cd $W && ls build.log bench.log *.err 2>/dev/null)
date >> $T
