#!/bin/bash
# Device call 7 (carry .fcl-debs and .gpu-data): mutation check of the new tests, on the tree of
# 8ac6595 with call7-mutations.diff applied (a host result from the stage one pair short; the rule's
# memory of the last host result always 0). Builds test_cuda_query and runs the one-trip,
# counting-order and joint tests (float); they must fail.
cd "$(dirname "$0")/../../.."
set -u
mkdir -p /tmp/m7
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
OUT=/tmp/m7 CTEST_ALL=0 JOBS=16 TARGETS="test_cuda_query" scripts/gpu_check.sh > /tmp/m7/check.log 2>&1
echo "check rc=$?" > $OUT/times.txt
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
build-gpu/tests/test_cuda_query --gtest_filter='CudaQueryTyped/0.OneTrip*:CudaQueryTyped/0.PairsAreOrdered*:CudaQueryTyped/0.IntersectAll*' > $OUT/mut.log 2>&1
echo "tests rc=$?" >> $OUT/times.txt
