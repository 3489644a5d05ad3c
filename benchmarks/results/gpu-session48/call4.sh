#!/bin/bash
# Device call 4 of session 48 (carry .fcl-debs/root and .gpu-data; a fresh machine): the forecast
# test's new case (the partner moved to another address and back keeps a's pairs forecast) on
# the tree, then with tenure.diff (session 47's tenure restored: a partner named by its entry's
# tenure), where that case must fail; ab_without rebuilds the tree's test after it.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_configure /tmp/s48c4
ab_targets test_cuda_query
F='*ANewMeshAtAFreed*:*ForecastReadsThePairs*:*NewMeshesAtTheSameAddress*'
ab_gtest tree "$F"
ab_without benchmarks/results/gpu-session48/tenure.diff tenure "$F"
ab_gtest tree-again "$F"
cp $W/test-*.txt $OUT/
date >> $T
