#!/bin/bash
# Device call 4 (carry .fcl-debs/root and .gpu-data): the warp-wide scans that test spans at 7 or
# 6 blocks per SM (experiment KDET_FCL_CUDA_WARP_BLOCKS: at most 72 or 80 registers, against 64;
# the double self scan then spills nothing, the float one less) against the defaults and a placebo
# knob: the frame probe (session 42's), profiling off and on; gpu_bench's cloth ball, two
# processes per form in turn. No test run (the knob only changes the kernels' register cap).
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_build /tmp/s44c4 gpu_bench
ab_probe "base;KDET_FCL_CUDA_WARP_BLOCKS=7;KDET_FCL_CUDA_WARP_BLOCKS=6;KDET_FCL_CUDA_TILE=8" \
  unc-cloth-ball unc-funnel unc-n-body cloth-20k cloth-90k cloth-250k cloth-1000k chair
ab_wait
ab_ball KDET_FCL_CUDA_WARP_BLOCKS 2 8 7 6
ab_finish
