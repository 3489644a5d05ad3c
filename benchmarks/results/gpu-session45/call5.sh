#!/bin/bash
# Device call 5 (carry .fcl-debs/root and .gpu-data): kdet_bench's GPU table on the tree with the
# scan's grouped cells (groups.diff): issue 5's ratios to the LBVH, in the same process, on the
# UNC and cloth scenes, the 1M cloth included, as session 43's call 3 ran it.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_configure /tmp/s45c5
cmake --build build-gpu --parallel 16 --target kdet_bench >> $W/build.log 2>&1
echo "build rc=$? $(date +%T)" >> $T
timeout 130 build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree \
  --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only unc,cloth --out $W/bench \
  > $W/bench.log 2>&1
echo "kdet_bench rc=$? $(date +%T)" >> $T
python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench/bench.json > $OUT/table.md 2>&1
tar czf $OUT/bench.tgz -C $W bench bench.log
date >> $T
