#!/bin/bash
# Prepared in session 47 for the next device session; not run. (carry .fcl-debs/root and
# .gpu-data; about 6 minutes.)
# Question: do kdet_bench's kDet GPU frames gain when commitVertices checks arrays of 0.75-1.5 MB
# in several threads? The UNC cloth ball's 1.1 MB of double positions are checked by one thread
# today (src/cpu/parallel.h: several only from 1.5 MB, 512 KB a thread), and its update column
# took 0.051-0.124 ms on an H100's host (session 47's call 5, median 0.067) against the LBVH's
# 0.02-0.04: kDet's cloth ball sat at a median 2.94x the LBVH there, 3.24x on an H200.
# next_threads.diff: 256 KB a thread from 768 KB (4 threads at 1.1 MB; still none on hosts of
# fewer than 3 threads, as CI's).
#   A: the tree; B: the tree with next_threads.diff, built beside it from a copy in /tmp/b.
#   1. update_bench --double (grid sides 215 and 300: 1.1 and 2.2 MB), A B A B;
#   2. kdet_bench's GPU table on the cloth-ball scenes and the 90k cloth, A B five times.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
rm -rf /tmp/b && mkdir -p /tmp/b
tar cf - --exclude=./build-gpu --exclude=./.gpu-data --exclude=./.fcl-debs --exclude=./build . |
  tar xf - -C /tmp/b
(cd /tmp/b && git apply benchmarks/results/gpu-session47/next_threads.diff) > /tmp/b-apply.txt 2>&1
B_APPLY=$?
# B's configure first, with its own times file (ab_configure starts $T afresh).
(cd /tmp/b && T=/tmp/next-b/times.txt ab_configure /tmp/next-b)
ab_configure /tmp/next
cat /tmp/b-apply.txt >> $T
echo "diff into /tmp/b rc=$B_APPLY $(date +%T)" >> $T
(cd /tmp/b && cmake --build build-gpu --parallel 8 --target kdet_bench update_bench \
  > /tmp/next-b/build.log 2>&1; echo "B build rc=$? $(date +%T)" >> $T) &
cmake --build build-gpu --parallel 8 --target kdet_bench update_bench >> $W/build.log 2>&1
echo "A build rc=$? $(date +%T)" >> $T
wait
# Each variant's binaries with its own library (LD_LIBRARY_PATH, which ab_common.sh points at
# A's build-gpu, comes before a binary's own run path).
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
cat $W/update-*.txt > $OUT/update.txt
tar czf $OUT/logs.tgz -C $W --exclude='*.json' .
date >> $T
