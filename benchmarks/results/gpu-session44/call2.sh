#!/bin/bash
# Device call 2 (carry .fcl-debs/root and .gpu-data): the cells' pairs without their box test
# where they test spans (experiment KDET_FCL_CUDA_CELL_BOXES=0: the pairs whose spans overlap go
# to the plane filter) against the defaults and a placebo knob. test_cuda_query whole under the
# knob (the tests that compare candidate counts with the scan's are expected to differ); the frame
# probe (session 42's), profiling off and on; gpu_bench's cloth ball, three processes per form.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_build /tmp/s44c2 gpu_bench test_cuda_query
ab_probe "base;KDET_FCL_CUDA_CELL_BOXES=0;KDET_FCL_CUDA_TILE=8" unc-cloth-ball unc-funnel \
  unc-n-body cloth-20k cloth-90k cloth-250k cloth-1000k chair
ab_wait
KDET_FCL_CUDA_CELL_BOXES=0 build-gpu/tests/test_cuda_query --gtest_filter="*Cells*:*SparseCells*" > $W/test-cells.txt 2>&1
echo "cells tests rc=$? $(date +%T)" >> $T
tail -n 3 $W/test-cells.txt >> $T
KDET_FCL_CUDA_CELL_BOXES=0 timeout 150 build-gpu/tests/test_cuda_query > $W/test-boxes.txt 2>&1
echo "test_cuda_query under CELL_BOXES=0 rc=$? $(date +%T)" >> $T
tail -n 3 $W/test-boxes.txt >> $T
ab_ball KDET_FCL_CUDA_CELL_BOXES 3 1 0
ab_finish
