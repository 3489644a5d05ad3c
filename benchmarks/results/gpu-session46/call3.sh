#!/bin/bash
# Device call 3 of session 46 (carry .fcl-debs/root and .gpu-data), on the tree with the cells'
# groups (groups.diff) and the fix of nextVisit (fix.diff: a lane looks on past a cell whose
# groups it skips whole):
#   1. the new test AWarpScanLooksOnPastACellWhoseGroupsItSkipsWhole and the groups' test;
#   2. kdet_bench's GPU table of call 1 (unc,cloth): the n-body pair must now agree;
#   3. fix.diff taken back (git apply -R), test_cuda_query rebuilt: the new test must fail.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_configure /tmp/s46c3
ab_targets test_cuda_query kdet_bench
F='*AWarpScanLooksOnPast*:*CountingBuildsGroupEachCellsEntries*'
build-gpu/tests/test_cuda_query --gtest_filter="$F" > $W/test-fixed.txt 2>&1
echo "tests (fixed) rc=$? $(date +%T)" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[       OK|^\[  FAILED" $W/test-fixed.txt >> $T
ab_table
cp $W/bench/bench.md $OUT/bench.md
git apply -R benchmarks/results/gpu-session46/fix.diff >> $T 2>&1
echo "fix.diff taken back rc=$? $(date +%T)" >> $T
cmake --build build-gpu --parallel 16 --target test_cuda_query >> $W/build.log 2>&1
echo "build (unfixed) rc=$? $(date +%T)" >> $T
build-gpu/tests/test_cuda_query --gtest_filter='*AWarpScanLooksOnPast*' > $W/test-unfixed.txt 2>&1
echo "test (unfixed) rc=$? $(date +%T)" >> $T
grep -E "^\[       OK|^\[  FAILED|lanes" $W/test-unfixed.txt | head -20 >> $T
git apply benchmarks/results/gpu-session46/fix.diff
cp $W/test-fixed.txt $W/test-unfixed.txt $OUT/
tar czf $OUT/logs.tgz -C $W bench.log build.log
date >> $T
