#!/bin/bash
# Session 49, call 4 (fresh machine; carry .fcl-debs/root and .gpu-data): bb5b5f0's GPU
# check (scripts/gpu_check.sh: ctest -L cuda, memcheck and racecheck, whose filter now includes
# the graph's moved-buffers test, gpu_bench on the cloth ball), then, if time is left, the
# forward probe on the 90k cloth with CUDA's modules loaded eagerly and lazily (the default):
# are the first pass's slow frames 2 and 3 (call 3) the kernels' lazy loading?
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
. benchmarks/results/gpu-session48/probe_build.sh
W=/tmp/s49
mkdir -p $W
rm -rf build-gpu
ab_check
probe_build benchmarks/results/gpu-session49/forward_probe.cpp $W/fprobe  # (inline in the run)
for m in EAGER LAZY; do
  CUDA_MODULE_LOADING=$m FRAMES=20 timeout 20 $W/fprobe cloth-90k 2>&1 | grep -v "^kdet_bench:" \
    > $OUT/fwd-90k-$m.txt
  echo "forward 90k $m rc=${PIPESTATUS[0]} $(date +%T)" >> $T
done
date >> $T
tar czf $OUT/check.tgz -C $OUT check && rm -rf $OUT/check
