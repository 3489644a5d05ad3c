#!/bin/bash
# Device call 4 (carry .fcl-debs/root and .gpu-data): the project's GPU check on the tree with the
# scan's grouped cells (groups.diff; the cells' skip of call 3 taken back), as a user with an
# offline GPU box runs it: scripts/gpu_check.sh with the CUDA tests' and gpu_bench's targets,
# ctest -L cuda, compute-sanitizer memcheck and racecheck (its filter now includes the groups'
# test), and gpu_bench on the UNC cloth ball (issue 4's targets: the frame, and its two frames as
# one query).
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_check
