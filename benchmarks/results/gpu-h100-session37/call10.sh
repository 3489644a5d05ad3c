#!/bin/bash
# Device call 10 (warm machine after call 9, which built the mutant at /tmp/mut/b): the tree's
# gpu_bench against the mutant's (topology shortcut off), GPU only, in turn, five rounds, on the
# cloth ball, the two cloth-ball frames and the 1M cloth. (gpu_bench's kDet re-hashes through
# cuda::markDeformed, which never compared the triangles: this checks the tree for no change there.)
# An earlier try of it (3 rounds, same command) brought back only 8 of its files.
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu KDET_FCL_DATA_DIR=$PWD/.gpu-data
ls /tmp/mut/b/benchmarks/gpu_bench build-gpu/benchmarks/gpu_bench || exit 3
mkdir -p /tmp/ab
for r in 1 2 3 4 5; do for v in tree mutant; do
  B=build-gpu/benchmarks/gpu_bench; [ $v = mutant ] && B=/tmp/mut/b/benchmarks/gpu_bench
  timeout 60 $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --only cloth-1000k \
    --csv /tmp/ab/ab-$v-$r.csv > /tmp/ab/ab-$v-$r.log 2>&1
  echo "round $r $v rc=$?"
done; done
tar czf $OUT/ab.tgz -C /tmp/ab .
