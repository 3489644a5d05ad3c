#!/bin/bash
# Device call 3 (carry .fcl-debs and .gpu-data; 600 s): the exact kernels' pairs spread over every
# warp (KDET_FCL_CUDA_EXACT_SPREAD, default 1) and the exact test's 2D branch for coplanar proper
# pairs (coplanarProper), on the tree of call 2. Builds the CUDA tests and gpu_bench; ctest -L
# cuda; gpu_bench (GPU only) in six rounds alternating the knob (1, 0) on the UNC cloth ball and
# n-body scenes and the 200k and 1M cloths; then ncu's durations of the exact kernels (clocks
# unlocked) on the cloth ball and its two frames, with the knob at 1 and at 0.
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
  timeout 330 scripts/gpu_check.sh > $W/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -30 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
B=build-gpu/benchmarks/gpu_bench
r=0
for R in 1 0 1 0 1 0; do
  left=$((500 - ($(date +%s) - START)))
  if [ $left -lt 60 ]; then echo "bench round $((r + 1)) skipped (time)" >> $T; break; fi
  r=$((r + 1))
  KDET_FCL_CUDA_EXACT_SPREAD=$R timeout 60 $B --no-fcl --no-cpu --repeats 20 \
    --only unc-cloth-ball --only unc-n-body --only cloth-200k --only cloth-1000k \
    --csv $W/bench-$r.csv >> $W/bench.log 2>&1
  echo "bench round $r (exact spread $R) rc=$?" >> $T
  if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,spread,/' > $OUT/bench.csv; fi
  tail -n +2 $W/bench-$r.csv | sed "s/^/$r,$R,/" >> $OUT/bench.csv
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in unc-cloth-ball-self unc-cloth-ball-2frames; do
  for R in 1 0; do
    left=$((575 - ($(date +%s) - START)))
    if [ $left -lt 25 ]; then echo "ncu $sc $R skipped (time)" >> $T; continue; fi
    KDET_FCL_CUDA_EXACT_SPREAD=$R timeout $((left - 5)) $NCU --clock-control none \
      --kernel-name regex:"Exact" --metrics gpu__time_duration.sum,launch__grid_size \
      --csv --print-units base $B --no-fcl --no-cpu --repeats 3 --only $sc \
      > $W/exact-$sc-$R.csv 2> $W/exact-$sc-$R.err
    echo "ncu $sc spread $R rc=$?" >> $T
    cp $W/exact-$sc-$R.csv $OUT/
  done
done
tar czf $OUT/logs.tgz -C $W check.log ctest.log bench.log $(cd $W && ls build.log *.err 2>/dev/null)
date >> $T
