#!/bin/bash
# Device call 3 (carry .fcl-debs/root and .gpu-data): the groups used by the cells' pairs too
# (each row's partners across the cell from its own group skipped). The frame probe in blocks
# of 4 frames per form (groups on y, the default, against none), profiling on; the groups' and
# the counting build's tests, then test_cuda_query whole; memcheck and racecheck of the groups'
# test (float); ncu's kernel durations of gpu_bench's cloth ball per form; gpu_bench's cloth
# ball, three processes per form, the form alternating.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_build /tmp/s45c3 gpu_bench test_cuda_query
BLOCK=4 PROFILE=1 FORMS="base;KDET_FCL_CUDA_CELL_GROUPS=0" ROUNDS=13 timeout 200 $W/probe \
  unc-cloth-ball unc-funnel unc-n-body cloth-90k cloth-250k > $W/probe-on.txt 2>&1
echo "probe on rc=$? $(date +%T)" >> $T
ab_wait
build-gpu/tests/test_cuda_query --gtest_filter='*Group*:*Counting*:*Cells*:*Knob*' > $W/test-groups.txt 2>&1
echo "groups tests rc=$? $(date +%T)" >> $T
tail -n 3 $W/test-groups.txt >> $T
timeout 150 build-gpu/tests/test_cuda_query > $W/test-all.txt 2>&1
echo "test_cuda_query rc=$? $(date +%T)" >> $T
tail -n 3 $W/test-all.txt >> $T
for tool in memcheck racecheck; do
  timeout 150 /usr/local/cuda/bin/compute-sanitizer --tool $tool --error-exitcode 3 \
    build-gpu/tests/test_cuda_query --gtest_filter='CudaQueryTyped/0.CountingBuildsGroup*' \
    > $W/$tool.txt 2>&1
  echo "$tool rc=$? $(date +%T)" >> $T
  tail -n 2 $W/$tool.txt >> $T
done
for g in 0 2; do
  ab_ncu KDET_FCL_CUDA_CELL_GROUPS $g $W/ncu-$g.csv
  gzip -c $W/ncu-$g.csv > $OUT/ncu-$g.csv.gz
done
ab_ball KDET_FCL_CUDA_CELL_GROUPS 3 0 2
ab_finish
