#!/bin/bash
# Device call 8 (carry .fcl-debs and .gpu-data): the final tree's check after the last code
# change (upload and download thread counts through one function, threadsFor): test_cuda_upload
# and test_cuda_query, the latter also with 4 KiB copy chunks on 4 threads (as ctest's
# test_cuda_query_small_copy_chunks), so that every pair list of more than 2,048 pairs into a
# kept result goes by the pool.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/c8
OUT=/tmp/c8 CTEST_ALL=0 JOBS=16 TARGETS="test_cuda_upload test_cuda_query" scripts/gpu_check.sh \
  > /tmp/c8/check.log 2>&1
echo "build rc=$? (ctest of the unbuilt CUDA tests fails: two were built)" >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
build-gpu/tests/test_cuda_upload > $OUT/test_cuda_upload.log 2>&1
echo "test_cuda_upload rc=$?" >> $T; tail -1 $OUT/test_cuda_upload.log >> $T
build-gpu/tests/test_cuda_query > /tmp/c8/test_cuda_query.log 2>&1
echo "test_cuda_query rc=$?" >> $T; tail -1 /tmp/c8/test_cuda_query.log >> $T
KDET_FCL_CUDA_UPLOAD_CHUNK=4096 KDET_FCL_CUDA_UPLOAD_THREADS=4 KDET_FCL_CUDA_DOWNLOAD_CHUNK=4096 \
  build-gpu/tests/test_cuda_query > /tmp/c8/test_cuda_query_small.log 2>&1
echo "test_cuda_query (4 KiB chunks) rc=$?" >> $T; tail -1 /tmp/c8/test_cuda_query_small.log >> $T
tar czf $OUT/logs.tgz -C /tmp/c8 check.log test_cuda_query.log test_cuda_query_small.log
date >> $T
