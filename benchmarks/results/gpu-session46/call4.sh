#!/bin/bash
# Device call 4 of session 46 (carry .fcl-debs/root and .gpu-data): the project's GPU check on
# the tree to commit (the cells' groups back, with nextVisit's fix and its test), as a user with
# an offline GPU box runs it: scripts/gpu_check.sh with the CUDA tests' and gpu_bench's targets,
# ctest -L cuda, compute-sanitizer memcheck and racecheck (the filter now includes the new test),
# and gpu_bench on the UNC cloth ball (session 44's ab_check).
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_check
