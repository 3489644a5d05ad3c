#!/bin/bash
# Device call 4 (carry .fcl-debs/root and .gpu-data): the project's GPU check on the tree with the
# scan's grouped cells (groups.diff; the cells' skip of call 3 taken back), as a user with an
# offline GPU box runs it: scripts/gpu_check.sh with the CUDA tests' and gpu_bench's targets,
# ctest -L cuda, compute-sanitizer memcheck and racecheck (its filter now includes the groups'
# test), and gpu_bench on the UNC cloth ball (issue 4's targets: the frame, and its two frames as
# one query).
set -u
cd "$(dirname "$0")/../../.."
date > $OUT/times.txt
OUT=$OUT/check CTEST_ALL=0 SANITIZER=1 GPU_BENCH=1 \
  GPU_BENCH_ARGS="--no-fcl --no-cpu --repeats 20 --only unc-cloth-ball" \
  TARGETS="test_cuda_device test_cuda_query test_cuda_bvh test_cuda_upload test_cuda_box_test test_cuda_warp_search test_cuda_predicates gpu_bench" \
  timeout 570 scripts/gpu_check.sh > $OUT/gpu_check.log 2>&1
echo "gpu_check rc=$? $(date +%T)" >> $OUT/times.txt
gzip -f $OUT/check/ctest.log $OUT/check/build.log 2>/dev/null
date >> $OUT/times.txt
