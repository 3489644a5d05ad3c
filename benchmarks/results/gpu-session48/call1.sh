#!/bin/bash
# Device call 1 of session 48 (carry .fcl-debs/root and .gpu-data; an H100; about 8 minutes).
# Session 47's next_check.sh, with the tree's change of this session checked first:
#   0. the tree (A) names an inter query's partner by its HashedMesh::identity() and drops the
#      cache entries' tenure: the forecast tests on it (test_cuda_query, the filter below);
#   1. does commitVertices' check of a 0.75-1.5 MB array pay in several threads? B: the tree with
#      threads.diff (session 47's next_threads.diff: 256 KB a thread from 768 KB, 4 threads at
#      the UNC cloth ball's 1.1 MB of double positions; still one thread on hosts of fewer than
#      3 threads), built beside A from a copy in /tmp/b. ldd shows each binary's own library;
#      update_bench --double (1.1 and 2.2 MB) A B A B; kdet_bench's GPU table on the cloth-ball
#      scenes and the 90k cloth, A B five times.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
rm -rf /tmp/b && mkdir -p /tmp/b
tar cf - --exclude=./build-gpu --exclude=./.gpu-data --exclude=./.fcl-debs --exclude=./build . |
  tar xf - -C /tmp/b
(cd /tmp/b && git apply benchmarks/results/gpu-session48/threads.diff) > /tmp/b-apply.txt 2>&1
B_APPLY=$?
# B's configure first, with its own times file (ab_configure starts $T afresh).
(cd /tmp/b && T=/tmp/s48b/times.txt ab_configure /tmp/s48b)
ab_configure /tmp/s48
cat /tmp/b-apply.txt >> $T
echo "threads.diff into /tmp/b rc=$B_APPLY $(date +%T)" >> $T
(cd /tmp/b && cmake --build build-gpu --parallel 7 --target kdet_bench update_bench \
  > /tmp/s48b/build.log 2>&1; echo "B build rc=$? $(date +%T)" >> $T) &
cmake --build build-gpu --parallel 9 --target kdet_bench update_bench test_cuda_query >> $W/build.log 2>&1
echo "A build rc=$? $(date +%T)" >> $T
wait
ab_gtest forecasts '*ANewMeshAtAFreed*:*ForecastReadsThePairs*:*NewMeshesAtTheSameAddress*:*IntersectAllHashesTwoMeshes*:*OneTripBrings*:*ResultsKeptAcrossFrames*'
tree_of() { if [ $1 = B ]; then echo /tmp/b; else echo $PWD; fi; }
run_v() {
  local d=$(tree_of $1)
  shift
  env LD_LIBRARY_PATH=$L:$d/build-gpu timeout 60 $d/build-gpu/benchmarks/"$@"
}
for v in A B; do
  d=$(tree_of $v)
  env LD_LIBRARY_PATH=$L:$d/build-gpu ldd $d/build-gpu/benchmarks/kdet_bench | grep kdet_fcl \
    | sed "s/^/$v: /" >> $T
done
for r in 1 2; do
  for v in A B; do
    run_v $v update_bench --double --reps 200 --max-n 300 > $W/update-$v-$r.txt 2>&1
    echo "update_bench $v $r rc=$? $(date +%T)" >> $T
  done
done
for r in 1 2 3 4 5; do
  for v in A B; do
    run_v $v kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree \
      --no-plots --methods 'kdet_gpu$,gpu_bvh$' --only unc-cloth-ball,cloth-90k \
      --out $W/bench-$v-$r > $W/bench-$v-$r.log 2>&1
    echo "kdet_bench $v $r rc=$? $(date +%T)" >> $T
    grep -h "DISAGREEMENT \*\*\*\|UNSTEADY" $W/bench-$v-$r.log >> $T
    python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-$v-$r/bench.json \
      > $W/table-$v-$r.md 2>&1
    grep -E "^\| (unc-cloth-ball|cloth-90k)" $W/table-$v-$r.md | sed "s/^/$v $r /" >> $OUT/runs.md
  done
done
for v in A B; do for r in 1 2; do echo "== $v $r"; cat $W/update-$v-$r.txt; done; done > $OUT/update.txt
cp $W/test-forecasts.txt $OUT/
tar czf $OUT/logs.tgz -C $W --exclude='*.json' .
date >> $T
