#!/bin/bash
# Session 49, call 3 (fresh machine; carry .fcl-debs/root and .gpu-data): the re-hash graph
# updated in place (cudaGraphExecUpdate) when its buffers moved, and a simulation going forward.
#   1. the library, test_cuda_query and forward_probe.cpp;
#   2. the re-hash graph's tests (the new ARehashGraphWhoseBuffersMoved..., the graph's replay
#      test, the outgrown test, the re-hash fallbacks), then memcheck on the new test;
#   3. forward_probe on the 90k cloth (20 frames) and the 250k cloth, each in its own process,
#      with KDET_FCL_CUDA_GRAPH_UPDATE=1 and 0 alternating, two processes each on the 90k cloth.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
. benchmarks/results/gpu-session48/probe_build.sh
W=/tmp/s49
ab_configure $W
ab_targets kdet_fcl test_cuda_query
probe_build benchmarks/results/gpu-session49/forward_probe.cpp $W/fprobe  # (inline in the run)
ab_gtest graph 'CudaQuery.ARehashGraph*:CudaQuery.RehashGraph*:CudaQuery.AMeshThatOutgrows*:CudaQuery.RehashWithout*:CudaQueryTyped/*.ANewMeshAtAFreed*'
grep -E "Failure|Which is|Expected|actual" $W/test-graph.txt | head -40 >> $T
SAN="$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)"
timeout 120 $SAN --tool memcheck build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQuery.ARehashGraphWhoseBuffersMoved*' > $W/memcheck.txt 2>&1
echo "memcheck rc=$? $(date +%T): $(grep 'ERROR SUMMARY' $W/memcheck.txt)" >> $T
forward_ab KDET_FCL_CUDA_GRAPH_UPDATE u 2 2  # (inline in the run)
date >> $T
tar czf $OUT/out.tgz -C $W --exclude=fprobe .
