#!/bin/bash
# Session 17 call 1: build gpu_bench, ncu durations of every kernel (1M cloth, cloth ball, two frames).
set -u
cd "$(dirname "$0")/../../.."
FINAL=$OUT
OUT=$FINAL/w
mkdir -p $OUT
trap 'cp $OUT/times.txt $FINAL/times.txt; tar czf $FINAL/out.tgz -C $FINAL w && rm -rf $FINAL/w' EXIT
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
OUT=$OUT/check CTEST_ALL=0 TARGETS="gpu_bench" JOBS=16 scripts/gpu_check.sh > $OUT/check.log 2>&1
echo "check rc=$?" >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
B=build-gpu/benchmarks/gpu_bench
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
$B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball-self --only cloth-1000k --csv $OUT/base.csv > $OUT/base.log 2>&1
echo "base rc=$?" >> $T
for sc in cloth-1000k unc-cloth-ball-self unc-cloth-ball-2frames; do
  timeout 150 $NCU --clock-control none --metrics gpu__time_duration.sum,launch__grid_size,launch__registers_per_thread --csv --print-units base \
    $B --no-fcl --no-cpu --repeats 1 --only $sc > $OUT/dur-$sc.csv 2> $OUT/dur-$sc.err
  echo "ncu $sc rc=$?" >> $T; date >> $T
done
