#!/bin/bash
# Session 50, call 3 (fresh machine; carry .fcl-debs/root and .gpu-data): are a forward
# simulation's slow frames 2 and 3 (session 49) the vertex buffers' registration as page-locked
# memory on their second upload? QueryProfile::host_registrations and host_register_ms (new)
# time it on the host.
#   1. the library and test_cuda_query; the registration tests, which now assert the counts;
#   2. session 49's forward_probe.cpp with forward_probe.diff (the graph-update column replaced
#      by the registrations), on the 90k cloth (20 frames): three processes as the tree runs,
#      two with KDET_FCL_CUDA_PIN_VERTICES=0 (no registration: every upload staged), alternating;
#      then the 250k cloth (12 frames) once each way.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
. benchmarks/results/gpu-session48/probe_build.sh
W=/tmp/s50
ab_configure $W
ab_targets kdet_fcl test_cuda_query
forward_probe_build benchmarks/results/gpu-session50/forward_probe.diff  # (inline in the run)
ab_gtest pin 'CudaQuery.LargeVertexArraysAreCopiedStraight*:CudaQuery.CommittedVerticesAreUploaded*:CudaQuery.ACommitCopies*'
grep -E "Failure|Which is|Expected|actual" $W/test-pin.txt | head -40 >> $T
forward_ab KDET_FCL_CUDA_PIN_VERTICES pin 3 2  # (inline in the run)
date >> $T
tar czf $OUT/out.tgz -C $W --exclude=fprobe --exclude=forward_probe.cpp .
