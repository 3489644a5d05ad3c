#!/bin/bash
# Device call 11 (carry .fcl-debs/root and .gpu-data; 600 s): the final library tree.
# scripts/gpu_check.sh with the CUDA label only (every CUDA test program, memcheck-free), then
# kdet_bench's smoke configuration (--quick) with its GPU columns (every pair set checked).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/gc
OUT_SAVE=$OUT
OUT=$W CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh test_cuda_warp_search test_cuda_predicates test_hierarchy kdet_bench" \
  timeout 480 scripts/gpu_check.sh > $W.log 2>&1
echo "gpu_check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -20 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
timeout 90 build-gpu/benchmarks/kdet_bench --quick --no-plots --out $W/quick > $W/quick.log 2>&1
echo "kdet_bench --quick rc=$?" >> $T
date >> $T
cp $W.log $W/gpu_check.log
tar czf $OUT_SAVE/gc.tgz -C $W .
