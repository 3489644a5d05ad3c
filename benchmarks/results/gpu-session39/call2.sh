#!/bin/bash
# Device call 2 (carry .fcl-debs/root and .gpu-data; 600 s): the final library tree (kept worker
# threads; the vertex check split at 512 KB a thread from 1.5 MB). scripts/gpu_check.sh with the
# CUDA label only (every CUDA test program), then test_worker_pool, test_bad_input as one
# process (its out-of-memory tests run in forked children, whose pool is new) and
# test_hierarchy's HashedMesh tests (the threaded check at every share edge).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s39c2
mkdir -p $W
OUT_SAVE=$OUT
OUT=$W CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh test_cuda_warp_search test_cuda_predicates test_hierarchy test_bad_input test_worker_pool kdet_bench update_bench" \
  timeout 500 scripts/gpu_check.sh > $W/gpu_check.log 2>&1
echo "gpu_check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -20 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
for t in test_worker_pool test_bad_input; do
  timeout 40 build-gpu/tests/$t > $W/$t.log 2>&1
  echo "$t rc=$? $(grep -E '^\[  (PASSED|FAILED) ' $W/$t.log | tr '\n' ' ')" >> $T
done
timeout 40 build-gpu/tests/test_hierarchy --gtest_filter='HashedMesh.*' > $W/test_hierarchy.log 2>&1
echo "test_hierarchy rc=$? $(grep -E '^\[  (PASSED|FAILED) ' $W/test_hierarchy.log | tr '\n' ' ')" >> $T
date >> $T
tar czf $OUT_SAVE/logs.tgz -C $W .
