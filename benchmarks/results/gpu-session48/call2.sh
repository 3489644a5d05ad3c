#!/bin/bash
# Device call 2 of session 48 (carry .fcl-debs/root and .gpu-data), on a fresh machine: the
# project's GPU check (scripts/gpu_check.sh as a user runs it: the CUDA tests, memcheck and
# racecheck, gpu_bench on the cloth ball) on the tree whose inter queries name their partner by
# its HashedMesh::identity() (the cache entries' tenure dropped).
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
rm -rf build-gpu
ab_check
