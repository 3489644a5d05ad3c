#!/bin/bash
# Device call 1 (carry .fcl-debs/root and .gpu-data): the cells' pairs by windows of 32 entries
# (KDET_FCL_CUDA_CELL_WINDOWS=1, off by default in this tree) against the rows' kernel (the
# default) and a placebo knob. The cells' tests and the knob test, test_cuda_query whole under
# the windows; the frame probe (session 42's), profiling off and on; gpu_bench's cloth ball,
# three processes per form, the form alternating.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_build /tmp/s44c1 gpu_bench test_cuda_query
ab_probe "base;KDET_FCL_CUDA_CELL_WINDOWS=1;KDET_FCL_CUDA_TILE=8" unc-cloth-ball unc-funnel \
  unc-n-body cloth-20k cloth-90k cloth-250k cloth-1000k nbody-181k chair
ab_wait
build-gpu/tests/test_cuda_query --gtest_filter='*Cells*:*Knob*:*SparseCells*' > $W/test-cells.txt 2>&1
echo "cells tests rc=$? $(date +%T)" >> $T
tail -n 3 $W/test-cells.txt >> $T
KDET_FCL_CUDA_CELL_WINDOWS=1 timeout 150 build-gpu/tests/test_cuda_query > $W/test-windows.txt 2>&1
echo "test_cuda_query under windows rc=$? $(date +%T)" >> $T
tail -n 3 $W/test-windows.txt >> $T
ab_ball KDET_FCL_CUDA_CELL_WINDOWS 3 0 1
ab_finish
