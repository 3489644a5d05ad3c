#!/bin/bash
# Device call 2 of session 47 (carry .fcl-debs/root and .gpu-data): the project's GPU check as a
# user runs it (scripts/gpu_check.sh: the CUDA tests' and gpu_bench's targets, ctest -L cuda,
# memcheck and racecheck on its filter, which now includes the new test, and gpu_bench on the
# UNC cloth ball), on the tree of call 1.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_check
