#!/bin/bash
# Device call 7 of session 48 (carry .fcl-debs/root and .gpu-data; a fresh machine; about 5
# minutes): a mesh that outgrows its hash's arrays gets half as much again of room in the build
# after the fallback (CachedMesh::outgrown, withRoom).
#   1. the tree: the new test AMeshThatOutgrowsItsHashGetsRoomForItsNextFrames and the re-hash
#      tests; precision_probe.cpp's first pass (FIRST=1 ROUNDS=0 ONLY=double: every frame new to
#      the meshes) on the 90k cloth and the cloth ball, three processes, with fallbacks counted;
#   2. outgrown.diff (no room after a fallback, as before): the new test (it must fail) and the
#      same three first passes. The machine is given back after this call, so the tree is not
#      rebuilt at the end.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
. benchmarks/results/gpu-session48/probe_build.sh  # (the run had its command inline)
ab_configure /tmp/s48c6
ab_targets test_cuda_query
ab_gtest tree '*Outgrows*:*Rehash*:*CountingBuild*'
probe_build
first() {
  for i in 1 2 3; do
    FIRST=1 ROUNDS=0 ONLY=double timeout 60 $W/probe cloth-90k unc-cloth-ball \
      2>&1 | grep -v "^kdet_bench:" > $W/first-$1-$i.txt
    echo "first pass $1 $i rc=$? $(date +%T)" >> $T
  done
}
first tree
git apply benchmarks/results/gpu-session48/outgrown.diff >> $T 2>&1
echo "outgrown.diff applied rc=$? $(date +%T)" >> $T
ab_targets test_cuda_query
ab_gtest without '*Outgrows*'
grep -E "Failure|Which is|Expected|actual|t = " $W/test-without.txt | head -40 >> $T
first without
for v in tree without; do for i in 1 2 3; do echo "== $v $i"; cat $W/first-$v-$i.txt; done; done \
  > $OUT/first.txt
cp $W/test-*.txt $OUT/
date >> $T
