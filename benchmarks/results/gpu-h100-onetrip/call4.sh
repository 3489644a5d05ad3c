#!/bin/bash
# Device call 4 (carry .fcl-debs and .gpu-data): why the one trip (KDET_FCL_CUDA_ONE_TRIP) lost
# 0.01-0.05 ms on the scenes whose pairs exceed one read-back chunk (cloth ball, two frames) in
# call 3 while it won elsewhere. gpu_bench on those two scenes, the knob on and off in turn, with
# kept and fresh results, and with one read-back thread; ncu's durations of the order's kernels.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/c4
OUT=/tmp/c4 CTEST_ALL=0 JOBS=16 TARGETS="gpu_bench" scripts/gpu_check.sh > /tmp/c4/check.log 2>&1
echo "check rc=$?" >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
B=build-gpu/benchmarks/gpu_bench
r=0
for V in kept fresh threads1; do
  for R in 1 0 1 0; do
    r=$((r + 1))
    X=""; E=""
    [ $V = fresh ] && X="--fresh-results"
    [ $V = threads1 ] && E="KDET_FCL_CUDA_DOWNLOAD_THREADS=1"
    env $E KDET_FCL_CUDA_ONE_TRIP=$R timeout 100 $B --no-fcl --no-cpu --repeats 20 $X \
      --only unc-cloth-ball-self --only unc-cloth-ball-2frames --only unc-n-body-self \
      --csv /tmp/c4/bench-$r.csv >> /tmp/c4/bench.log 2>&1
    echo "bench round $r ($V, one trip $R) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 /tmp/c4/bench-1.csv | sed 's/^/round,variant,one_trip,/' > $OUT/bench.csv; fi
    tail -n +2 /tmp/c4/bench-$r.csv | sed "s/^/$r,$V,$R,/" >> $OUT/bench.csv
  done
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for R in 1 0; do
  KDET_FCL_CUDA_ONE_TRIP=$R timeout 120 $NCU --clock-control none --metrics gpu__time_duration.sum,launch__grid_size \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 3 --only unc-cloth-ball-2frames > /tmp/c4/dur-$R.csv 2> /tmp/c4/dur-$R.err
  echo "ncu one trip $R rc=$?" >> $T
  echo "== one trip $R" >> $OUT/kernels.txt
  python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py /tmp/c4/dur-$R.csv >> $OUT/kernels.txt 2>&1
done
tar czf $OUT/logs.tgz -C /tmp/c4 check.log bench.log $(cd /tmp/c4 && ls dur-*.err dur-*.csv build.log 2>/dev/null)
date >> $T
