#!/bin/bash
# Device call 3 (carry .fcl-debs/root and .gpu-data; 600 s): the final library tree.
# scripts/gpu_check.sh with the CUDA label only (every CUDA test program), then test_bad_input
# as one process (its out-of-memory tests together with the rest, on a machine with a device),
# test_hierarchy's HashedMesh tests, and kdet_bench's smoke configuration (--quick) with its GPU
# columns (every pair set checked).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s38c3
mkdir -p $W
OUT_SAVE=$OUT
OUT=$W CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh test_cuda_warp_search test_cuda_predicates test_hierarchy test_bad_input kdet_bench" \
  timeout 470 scripts/gpu_check.sh > $W/gpu_check.log 2>&1
echo "gpu_check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -20 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
timeout 40 build-gpu/tests/test_bad_input > $W/test_bad_input.log 2>&1
echo "test_bad_input rc=$? $(grep -E '^\[  (PASSED|FAILED) ' $W/test_bad_input.log | tr '\n' ' ')" >> $T
timeout 40 build-gpu/tests/test_hierarchy --gtest_filter='HashedMesh.*' > $W/test_hierarchy.log 2>&1
echo "test_hierarchy rc=$? $(grep -E '^\[  (PASSED|FAILED) ' $W/test_hierarchy.log | tr '\n' ' ')" >> $T
timeout 60 build-gpu/benchmarks/kdet_bench --quick --no-plots --out $W/quick > $W/quick.log 2>&1
echo "kdet_bench --quick rc=$?" >> $T
date >> $T
tar czf $OUT_SAVE/logs.tgz -C $W .
