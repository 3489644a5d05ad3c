#!/bin/bash
# Device call 8 (carry .fcl-debs and .gpu-data): where the frames go after the one trip. ncu's kernel
# durations (clocks unlocked) of the 20k and 90k cloths, the funnel, the n-body and the cloth ball, summed per
# frame, against the frame's event time (gpu_bench, same binary, no profiler).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/c8
OUT=/tmp/c8 CTEST_ALL=0 JOBS=16 TARGETS="gpu_bench" \
  scripts/gpu_check.sh > /tmp/c8/check.log 2>&1
echo "check rc=$?" >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
B=build-gpu/benchmarks/gpu_bench
timeout 100 $B --no-fcl --no-cpu --repeats 20 --only cloth-20k --only cloth-90k --only unc-funnel-self \
  --only unc-n-body-self --only unc-cloth-ball-self --csv $OUT/bench.csv > /tmp/c8/bench.log 2>&1
echo "bench rc=$?" >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in cloth-20k cloth-90k unc-funnel-self unc-n-body-self unc-cloth-ball-self; do
  timeout 100 $NCU --clock-control none --metrics gpu__time_duration.sum,launch__grid_size,launch__registers_per_thread \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 3 --only $sc > /tmp/c8/dur-$sc.csv 2> /tmp/c8/dur-$sc.err
  echo "ncu $sc rc=$?" >> $T
  echo "== $sc" >> $OUT/kernels.txt
  python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py /tmp/c8/dur-$sc.csv >> $OUT/kernels.txt 2>&1
done
tar czf $OUT/logs.tgz -C /tmp/c8 check.log ctest.log bench.log $(cd /tmp/c8 && ls dur-*.err dur-*.csv 2>/dev/null)
date >> $T
