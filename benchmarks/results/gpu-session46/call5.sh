#!/bin/bash
# Device call 5 of session 46 (carry .fcl-debs/root and .gpu-data): kdet_bench's GPU table
# (unc,cloth, as call 3) on the tree as committed, whose kdet_bench now also compares every timed
# run's pair counts with its checking run's (*** UNSTEADY ***).
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_configure /tmp/s46c5
cmake --build build-gpu --parallel 16 --target kdet_bench >> $W/build.log 2>&1
echo "build rc=$? $(date +%T)" >> $T
timeout 130 build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree \
  --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only unc,cloth --out $W/bench \
  > $W/bench.log 2>&1
echo "kdet_bench rc=$? $(date +%T)" >> $T
grep -h "DISAGREEMENT \*\*\*\|UNSTEADY" $W/bench.log >> $T
cp $W/bench/bench.md $OUT/bench.md
python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench/bench.json > $OUT/table.md 2>&1
gzip -c $W/bench.log > $OUT/bench.log.gz
date >> $T
