#!/bin/bash
# Device call 1 of session 47 (carry .fcl-debs/root and .gpu-data), on the tree with the cache
# entries' forecasts dropped when a new mesh takes an entry over (CachedMesh::takeFor):
#   1. the new test ANewMeshAtAFreedMeshsAddressStartsWithoutItsForecasts, the forecast test that
#      now asserts first queries, and the tests of meshes at the same address and joint queries;
#   2. kdet_bench's GPU table (unc,cloth, 1M included, the LBVH in the same process);
#   3. the fix taken back (nofix.diff: an entry keeps its forecasts and its tenure for life, as
#      the tree before kept them), test_cuda_query rebuilt: the new test must fail.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
P=benchmarks/results/gpu-session47
ab_configure /tmp/s47c1
ab_targets test_cuda_query kdet_bench
F='*ANewMeshAtAFreed*:*ForecastReadsThePairs*:*NewMeshesAtTheSameAddress*:*IntersectAllHashesTwoMeshes*:*OneTripBrings*:*ResultsKeptAcrossFrames*'
build-gpu/tests/test_cuda_query --gtest_filter="$F" > $W/test-fixed.txt 2>&1
echo "tests (fixed) rc=$? $(date +%T)" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[       OK|^\[  FAILED" $W/test-fixed.txt >> $T
ab_table
cp $W/bench/bench.md $OUT/bench.md
git apply $P/nofix.diff >> $T 2>&1
echo "nofix.diff applied rc=$? $(date +%T)" >> $T
cmake --build build-gpu --parallel 16 --target test_cuda_query >> $W/build.log 2>&1
echo "build (unfixed) rc=$? $(date +%T)" >> $T
build-gpu/tests/test_cuda_query --gtest_filter='*ANewMeshAtAFreed*:*ForecastReadsThePairs*' \
  > $W/test-unfixed.txt 2>&1
echo "tests (unfixed) rc=$? $(date +%T)" >> $T
grep -E "^\[       OK|^\[  FAILED|Failure|Expected|Which is|: " $W/test-unfixed.txt | head -60 >> $T
git apply -R $P/nofix.diff
cp $W/test-fixed.txt $W/test-unfixed.txt $OUT/
tar czf $OUT/logs.tgz -C $W bench.log build.log
date >> $T
