#!/bin/bash
# Session 51, call 1 (fresh machine; carry .fcl-debs/root and .gpu-data): a vertex buffer's
# registration as page-locked memory on a thread of its own (KDET_FCL_CUDA_PIN_ASYNC, new,
# default on), the query going on with a staged upload.
#   1. the library and test_cuda_query; the registration and copy tests, the new background
#      one among them, five times; then all of test_cuda_query once; memcheck on the new test;
#   2. session 49's forward_probe.cpp with session 50's and this session's forward_probe.diff
#      (the background registrations and the DMA uploads per query): the 90k cloth (20 frames),
#      four processes with KDET_FCL_CUDA_PIN_ASYNC=1 and four with 0, alternating, then the
#      250k cloth (12 frames) once each way;
#   3. gpu_bench on the UNC cloth ball, one process each way (its frames repeat: the
#      registration has ended before they are timed).
# Ran on 1d44c28 with call1-async.diff applied (git apply benchmarks/results/gpu-session51/
# call1-async.diff; taken back after this call). It leaves more than the eight files the device
# returns under $OUT (the forward_ab runs write there), so times.txt and out.tgz did not come back.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
. benchmarks/results/gpu-session48/probe_build.sh
W=/tmp/s51
ab_configure $W
ab_targets kdet_fcl test_cuda_query gpu_bench
forward_probe_build benchmarks/results/gpu-session50/forward_probe.diff \
  benchmarks/results/gpu-session51/forward_probe.diff  # (inline in the run)
PIN='CudaQuery.LargeVertexArraysAreCopiedStraight*:CudaQuery.CommittedVerticesAreUploaded*'
PIN="$PIN:CudaQuery.ABackgroundRegistration*:CudaQuery.ACommitCopies*:CudaQuery.UpdateVerticesCopies*"
for r in 1 2 3 4 5; do
  ab_gtest pin$r "$PIN"
  grep -E "Failure|Which is|Expected|actual|\[ info" $W/test-pin$r.txt | head -20 >> $T
done
ab_gtest all '*'
grep -E "Failure|Which is|Expected|actual" $W/test-all.txt | head -40 >> $T
timeout 240 /usr/local/cuda/bin/compute-sanitizer --tool memcheck --leak-check full \
  build-gpu/tests/test_cuda_query --gtest_filter='CudaQuery.ABackgroundRegistration*' \
  > $W/memcheck.txt 2>&1
echo "memcheck rc=$? $(date +%T)" >> $T
grep -E "ERROR SUMMARY|LEAK SUMMARY|PASSED|FAILED" $W/memcheck.txt >> $T
forward_ab KDET_FCL_CUDA_PIN_ASYNC async 4 4
ab_ball KDET_FCL_CUDA_PIN_ASYNC 1 1 0
date >> $T
tar czf $OUT/out.tgz -C $W --exclude=fprobe --exclude=forward_probe.cpp --exclude='*.csv' .
