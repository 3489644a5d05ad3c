#!/bin/bash
# Device call 6 (carry .fcl-debs and .gpu-data): the builds' scans inside the kernels that make their
# counts (countScanKernel, cellsScanKernel: cooperative launches; KDET_FCL_CUDA_FUSED_SCANS, default
# 1). Builds the CUDA tests and gpu_bench; ctest -L cuda; memcheck and racecheck of the new test and
# the one-trip test (float); gpu_bench (GPU only) on the UNC scenes and the 20k, 90k, 250k and 1M
# cloths in six rounds alternating the knob (1, 0, ...); in the time left, ncu of the 20k cloth.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/c6
OUT=/tmp/c6 CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  scripts/gpu_check.sh > /tmp/c6/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/c6/ctest.log | head -30 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
F='CudaQueryTyped/0.BuildScans*:CudaQueryTyped/0.OneTripBrings*'
for tool in memcheck racecheck; do
  timeout 150 $SAN --tool $tool --error-exitcode 3 build-gpu/tests/test_cuda_query \
    --gtest_filter="$F" > /tmp/c6/$tool-new.log 2>&1
  echo "$tool ($F) rc=$?" >> $T; tail -2 /tmp/c6/$tool-new.log >> $T
done
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for R in 1 0 1 0 1 0; do
  r=$((r + 1))
  KDET_FCL_CUDA_FUSED_SCANS=$R timeout 100 $B --no-fcl --no-cpu --repeats 20 \
    --only unc --only cloth-20k --only cloth-90k --only cloth-250k --only cloth-1000k \
    --csv /tmp/c6/bench-$r.csv >> /tmp/c6/bench.log 2>&1
  echo "bench round $r (fused scans $R) rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/c6/bench-1.csv | sed 's/^/round,fused,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/c6/bench-$r.csv | sed "s/^/$r,$R,/" >> $OUT/bench.csv
done
date >> $T
# In the time left: ncu's kernel durations of the 20k cloth (gpu-h100-profile/kernels_per_frame.py).
left=$((560 - ($(date +%s) - START)))
if [ $left -gt 40 ]; then
  NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
  timeout $((left - 10)) $NCU --clock-control none --metrics gpu__time_duration.sum,launch__grid_size \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 3 --only cloth-20k > /tmp/c6/dur.csv 2> /tmp/c6/dur.err
  echo "ncu cloth-20k rc=$?" >> $T
  python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py /tmp/c6/dur.csv > $OUT/kernels.txt 2>&1
fi
date >> $T
tar czf $OUT/logs.tgz -C /tmp/c6 check.log ctest.log bench.log memcheck-new.log racecheck-new.log \
  $(cd /tmp/c6 && ls build.log 2>/dev/null)
date >> $T
