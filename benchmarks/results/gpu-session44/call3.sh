#!/bin/bash
# Device call 3 (carry .fcl-debs/root and .gpu-data): the project's GPU check on this session's
# final tree (no library change since session 43), as a user with an offline GPU box runs it:
# scripts/gpu_check.sh with the CUDA tests' and gpu_bench's targets, ctest -L cuda, compute-sanitizer
# memcheck and racecheck (its filter now includes the commit's and update's copy tests), and
# gpu_bench on the UNC cloth ball (issue 4's targets: the frame, and its two frames as one).
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_check
