#!/bin/bash
# Device call 1 (carry .fcl-debs and .gpu-data; 600 s): the counting order's scatter and rank
# loops folded into shared device functions (scatterKeys, rankKeys), a one-trip host result's
# pairs written to the mapped stage only; ctest -L cuda checks it. Then an A/B of the counting
# build's size limit (KDET_FCL_CUDA_COUNT_BUILD_MAX = 150000, the default, against 1200000) on the
# 200k, 250k and 1M cloths and the joint two-frame scenes (gpu_bench, GPU only, six rounds in
# turn); then ncu's durations and a few throughput metrics of every kernel of the 200k cloth.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c1
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
for R in 150000 1200000 150000 1200000 150000 1200000; do
  left=$((560 - ($(date +%s) - START)))
  if [ $left -lt 90 ]; then echo "bench round $((r + 1)) skipped (time)" >> $T; break; fi
  r=$((r + 1))
  KDET_FCL_CUDA_COUNT_BUILD_MAX=$R timeout 60 $B --no-fcl --no-cpu --repeats 20 \
    --only cloth-200k --only cloth-250k --only cloth-1000k --only unc-cloth-ball-2frames \
    --only unc-n-body-2frames --csv $W/bench-$r.csv >> $W/bench.log 2>&1
  echo "bench round $r (count build max $R) rc=$?" >> $T
  if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,count_max,/' > $OUT/bench.csv; fi
  tail -n +2 $W/bench-$r.csv | sed "s/^/$r,$R,/" >> $OUT/bench.csv
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
left=$((575 - ($(date +%s) - START)))
if [ $left -gt 30 ]; then
  timeout $((left - 5)) $NCU --clock-control none --metrics \
gpu__time_duration.sum,launch__grid_size,launch__registers_per_thread,sm__warps_active.avg.pct_of_peak_sustained_active,sm__cycles_active.avg.pct_of_peak_sustained_elapsed,sm__throughput.avg.pct_of_peak_sustained_elapsed,dram__throughput.avg.pct_of_peak_sustained_elapsed,lts__t_sector_hit_rate.pct \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 2 --only cloth-200k > $W/ncu-200k.csv 2> $W/ncu-200k.err
  echo "ncu cloth-200k rc=$?" >> $T
  echo "== cloth-200k" > $OUT/kernels.txt
  python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py $W/ncu-200k.csv >> $OUT/kernels.txt 2>&1
  gzip -c $W/ncu-200k.csv > $OUT/ncu-200k.csv.gz
fi
tar czf $OUT/logs.tgz -C $W check.log ctest.log bench.log $(cd $W && ls build.log ncu-200k.err 2>/dev/null)
date >> $T
