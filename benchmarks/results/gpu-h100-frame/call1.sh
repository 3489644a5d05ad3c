#!/bin/bash
# First device call of the session (carry .fcl-debs and .gpu-data): the tree of 08d399e.
# Builds gpu_bench only; a baseline (cloth ball, its two frames, the 90k and 1M cloths, the
# n-body, 20 repeats, twice); then ncu's durations of every kernel (clocks not locked) of the
# cloth ball, its two frames and the 1M cloth, summed per frame by
# ../gpu-h100-profile/kernels_per_frame.py: how much of each frame's event time the kernels fill.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 TARGETS="gpu_bench" scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$?" >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
B=build-gpu/benchmarks/gpu_bench
for r in 1 2; do
  timeout 100 $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --only unc-n-body \
    --only cloth-90k --only cloth-1000k --csv /tmp/chk/base-$r.csv >> /tmp/chk/bench.log 2>&1
  echo "base $r rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/chk/base-1.csv | sed 's/^/round,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/chk/base-$r.csv | sed "s/^/$r,/" >> $OUT/bench.csv
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in unc-cloth-ball-self unc-cloth-ball-2frames cloth-1000k; do
  timeout 150 $NCU --clock-control none --metrics gpu__time_duration.sum,launch__grid_size,launch__registers_per_thread \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 3 --only $sc > /tmp/chk/dur-$sc.csv 2> /tmp/chk/dur-$sc.err
  echo "ncu $sc rc=$?" >> $T
  echo "== $sc" >> $OUT/kernels.txt
  python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py /tmp/chk/dur-$sc.csv >> $OUT/kernels.txt 2>&1
  date >> $T
done
tar czf $OUT/logs.tgz -C /tmp/chk check.log bench.log $(cd /tmp/chk && ls dur-*.err build.log 2>/dev/null)
gzip -c /tmp/chk/dur-unc-cloth-ball-self.csv > $OUT/dur-cloth-ball.csv.gz
date >> $T
