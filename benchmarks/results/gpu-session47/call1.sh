#!/bin/bash
# Device call 1 of session 47 (carry .fcl-debs/root and .gpu-data), on the tree with the cache
# entries' forecasts dropped when a new mesh takes an entry over (CachedMesh::takeFor):
#   1. the new test ANewMeshAtAFreedMeshsAddressStartsWithoutItsForecasts, the forecast test that
#      now asserts first queries, and the tests of meshes at the same address and joint queries;
#   2. kdet_bench's GPU table (unc,cloth, 1M included, the LBVH in the same process);
#   3. the fix taken back (nofix.diff: an entry keeps its forecasts and its tenure for life, as
#      the tree before kept them), test_cuda_query rebuilt: the new test must fail.
# Written with ab_common.sh's ab_gtest and ab_without after the run (the same steps). The run
# itself did not rebuild test_cuda_query after taking nofix.diff back, which ab_without now does:
# call 2 then met the library built without the fix on the same machine (README.md).
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_configure /tmp/s47c1
ab_targets test_cuda_query kdet_bench
ab_gtest fixed '*ANewMeshAtAFreed*:*ForecastReadsThePairs*:*NewMeshesAtTheSameAddress*:*IntersectAllHashesTwoMeshes*:*OneTripBrings*:*ResultsKeptAcrossFrames*'
ab_table
cp $W/bench/bench.md $OUT/bench.md
ab_without benchmarks/results/gpu-session47/nofix.diff unfixed '*ANewMeshAtAFreed*:*ForecastReadsThePairs*'
cp $W/test-fixed.txt $W/test-unfixed.txt $OUT/
tar czf $OUT/logs.tgz -C $W bench.log build.log
date >> $T
