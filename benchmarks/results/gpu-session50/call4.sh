#!/bin/bash
# Session 50, call 4 (fresh machine; carry .fcl-debs/root and .gpu-data): the registration
# tests after call 3 (CommittedVerticesAreUploadedFromBothRegisteredBuffers now lets frame 1's
# fallback register the second buffer, as call 3's run met), five repeats; all of
# test_cuda_query; memcheck on the three registration tests.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
W=/tmp/s50
ab_configure $W
ab_targets kdet_fcl test_cuda_query
PIN='CudaQuery.LargeVertexArraysAreCopiedStraight*:CudaQuery.CommittedVerticesAreUploaded*:CudaQuery.ACommitCopies*'
build-gpu/tests/test_cuda_query --gtest_filter="$PIN" --gtest_repeat=5 > $W/test-pin.txt 2>&1
echo "tests (pin, 5 repeats) rc=$? $(date +%T)" >> $T
grep -cE "^\[       OK" $W/test-pin.txt >> $T
grep -E "Failure|Which is|Expected|actual|^frame" $W/test-pin.txt | head -40 >> $T
timeout 200 build-gpu/tests/test_cuda_query > $W/test-all.txt 2>&1
echo "test_cuda_query rc=$? $(date +%T)" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED|tests? from .* ran" $W/test-all.txt >> $T
SAN="$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)"
timeout 150 $SAN --tool memcheck build-gpu/tests/test_cuda_query --gtest_filter="$PIN" \
  > $W/memcheck.txt 2>&1
echo "memcheck rc=$? $(date +%T): $(grep 'ERROR SUMMARY' $W/memcheck.txt)" >> $T
date >> $T
gzip -c $W/test-all.txt > $OUT/test-all.txt.gz
cp $W/test-pin.txt $W/memcheck.txt $OUT/
gzip -c $W/build.log > $OUT/build.log.gz
