#!/bin/bash
# Session 51, call 5 (fresh machine; carry .fcl-debs/root and .gpu-data): a vertex buffer's
# registration deferred until the query's device work is queued (KDET_FCL_CUDA_PIN_DEFER, new,
# default on; the registering upload is staged), against the registration before the upload.
#   1. the library and test_cuda_query; the registration and copy tests three times; all of
#      test_cuda_query once; memcheck on the two registration tests;
#   2. session 49's forward_probe.cpp with session 50's diff and forward_probe_defer.diff: the
#      90k cloth (20 frames), four processes with KDET_FCL_CUDA_PIN_DEFER=1 and four with 0,
#      alternating, then the 250k cloth (12 frames) twice each way.
# Outputs: $OUT/times.txt, $OUT/frames.txt (frames 1-5 of every probe run), $OUT/out.tgz.
# Ran on ae62942 with call5-defer.diff applied (git apply benchmarks/results/gpu-session51/
# call5-defer.diff); taken back after this call.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
. benchmarks/results/gpu-session48/probe_build.sh
W=/tmp/s51e
ab_configure $W
ab_targets kdet_fcl test_cuda_query
forward_probe_build benchmarks/results/gpu-session50/forward_probe.diff \
  benchmarks/results/gpu-session51/forward_probe_defer.diff  # (inline in the run)
PIN='CudaQuery.LargeVertexArraysAreCopiedStraight*:CudaQuery.CommittedVerticesAreUploaded*'
PIN="$PIN:CudaQuery.ACommitCopies*:CudaQuery.UpdateVerticesCopies*:CudaQuery.EveryKnob*"
for r in 1 2 3; do
  ab_gtest pin$r "$PIN"
  grep -E "Failure|Which is|Expected|actual" $W/test-pin$r.txt | head -20 >> $T
done
ab_gtest all '*'
grep -E "Failure|Which is|Expected|actual" $W/test-all.txt | head -20 >> $T
timeout 200 /usr/local/cuda/bin/compute-sanitizer --tool memcheck build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQuery.LargeVertexArraysAreCopiedStraight*:CudaQuery.CommittedVerticesAreUploaded*' \
  > $W/memcheck.txt 2>&1
echo "memcheck rc=$? $(date +%T)" >> $T
grep -E "ERROR SUMMARY|PASSED|FAILED" $W/memcheck.txt >> $T
forward_runs KDET_FCL_CUDA_PIN_DEFER defer cloth-90k 20 4 60  # (inline in the run)
forward_runs KDET_FCL_CUDA_PIN_DEFER defer cloth-250k 12 2 90
for f in $W/fwd-*.txt; do echo "== $(basename $f)"; sed -n 1,7p $f; grep "^pass" $f; done > $OUT/frames.txt
date >> $T
tar czf $OUT/out.tgz -C $W --exclude=fprobe --exclude=forward_probe.cpp --exclude='*.log' .
