#!/bin/bash
# Device call 2 (carry .fcl-debs/root and .gpu-data): ncu's kernel durations (no clock control)
# of gpu_bench's cloth ball (its frame alone, then its two frames as one query) with the cells
# grouped on y (the default) and not grouped (KDET_FCL_CUDA_CELL_GROUPS=0): phase 1's kernels
# and the counting build's, two processes per form; then the groups' test.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_configure /tmp/s45c2
cmake --build build-gpu --parallel 16 --target gpu_bench test_cuda_query >> $W/build.log 2>&1
echo "build rc=$? $(date +%T)" >> $T
for g in 0 2 0 2; do
  ab_ncu KDET_FCL_CUDA_CELL_GROUPS $g $W/ncu-$g.csv
  cat $W/ncu-$g.csv >> $W/ncu-all-$g.csv
done
build-gpu/tests/test_cuda_query --gtest_filter='*Group*:*Counting*' > $W/test-groups.txt 2>&1
echo "groups tests rc=$? $(date +%T)" >> $T
tail -n 3 $W/test-groups.txt >> $T
gzip -f $W/ncu-all-*.csv
cp $W/ncu-all-*.csv.gz $OUT/
tar czf $OUT/out.tgz -C $W --exclude='*.csv' --exclude='*.gz' .
date >> $T
