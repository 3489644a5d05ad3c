#!/bin/bash
# Device call 1 (carry .fcl-debs/root and .gpu-data): cells grouped by halves on one axis in the
# counting build (KDET_FCL_CUDA_CELL_GROUPS: unset = y, 0 none, 1 x, 3 z). The frame probe
# (session 42's) in blocks of 4 frames per form (a form switch recaptures the re-hash graph),
# profiling on; the new test under memcheck; test_cuda_query whole; gpu_bench's cloth ball, three
# processes per form (none, y), the form alternating.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_build /tmp/s45c1 gpu_bench test_cuda_query
export BLOCK=4
PROFILE=1 FORMS="base;KDET_FCL_CUDA_CELL_GROUPS=0;KDET_FCL_CUDA_CELL_GROUPS=1;KDET_FCL_CUDA_CELL_GROUPS=3" \
  ROUNDS=13 timeout 200 $W/probe unc-cloth-ball unc-funnel unc-n-body cloth-90k cloth-250k \
  > $W/probe-on.txt 2>&1
echo "probe on rc=$? $(date +%T)" >> $T
unset BLOCK
ab_wait
build-gpu/tests/test_cuda_query --gtest_filter='*Group*:*Counting*:*Knob*' > $W/test-groups.txt 2>&1
echo "groups tests rc=$? $(date +%T)" >> $T
tail -n 3 $W/test-groups.txt >> $T
timeout 150 /usr/local/cuda/bin/compute-sanitizer --tool memcheck build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQueryTyped/0.CountingBuildsGroup*' > $W/memcheck.txt 2>&1
echo "memcheck rc=$? $(date +%T)" >> $T
tail -n 3 $W/memcheck.txt >> $T
timeout 150 build-gpu/tests/test_cuda_query > $W/test-all.txt 2>&1
echo "test_cuda_query rc=$? $(date +%T)" >> $T
tail -n 3 $W/test-all.txt >> $T
ab_ball KDET_FCL_CUDA_CELL_GROUPS 3 0 2
ab_finish
