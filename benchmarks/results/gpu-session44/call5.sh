#!/bin/bash
# Device call 5 (carry .fcl-debs/root and .gpu-data): the review mend (updateVertices' copy of a
# range in one helper) on the GPU: scripts/gpu_check.sh with the CUDA tests' targets and
# test_commit_copy, ctest -L cuda, then test_commit_copy.
set -u
cd "$(dirname "$0")/../../.."
date > $OUT/times.txt
OUT=$OUT/check CTEST_ALL=0 \
  TARGETS="test_cuda_device test_cuda_query test_cuda_bvh test_cuda_upload test_cuda_box_test test_cuda_warp_search test_cuda_predicates test_commit_copy" \
  timeout 500 scripts/gpu_check.sh > $OUT/gpu_check.log 2>&1
echo "gpu_check rc=$? $(date +%T)" >> $OUT/times.txt
build-gpu/tests/test_commit_copy > $OUT/test_commit_copy.txt 2>&1
echo "test_commit_copy rc=$? $(date +%T)" >> $OUT/times.txt
gzip -f $OUT/check/ctest.log $OUT/check/build.log 2>/dev/null
date >> $OUT/times.txt
