#!/bin/bash
# Device call 2 (carry .fcl-debs and .gpu-data): why call 1's one-trip queries failed in five
# tests with cudaErrorInvalidAddressSpace. Builds test_cuda_query; runs each failing test as is,
# with KDET_FCL_CUDA_ONE_TRIP=0, with CUDA_LAUNCH_BLOCKING=1, and under memcheck.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/c2
OUT=/tmp/c2 CTEST_ALL=0 JOBS=16 TARGETS="test_cuda_query" scripts/gpu_check.sh > /tmp/c2/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/c2/ctest.log | head -30 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
Q=build-gpu/tests/test_cuda_query
for F in CudaQuery.WarpAndTileScans* 'CudaQueryTyped/0.QueriesInRounds*' 'CudaQueryTyped/0.AllPairsOnTheDevice*'; do
  n=$(echo $F | tr -dc 'A-Za-z' | cut -c1-30)
  timeout 60 $Q --gtest_filter="$F" > /tmp/c2/$n-plain.log 2>&1; echo "$F plain rc=$?" >> $T
  KDET_FCL_CUDA_ONE_TRIP=0 timeout 60 $Q --gtest_filter="$F" > /tmp/c2/$n-off.log 2>&1; echo "$F one trip off rc=$?" >> $T
  KDET_FCL_CUDA_DOWNLOAD_CHUNK=4096 timeout 60 $Q --gtest_filter="$F" > /tmp/c2/$n-chunk4k.log 2>&1; echo "$F 4 KiB chunks rc=$?" >> $T
  CUDA_LAUNCH_BLOCKING=1 timeout 60 $Q --gtest_filter="$F" > /tmp/c2/$n-blocking.log 2>&1; echo "$F blocking rc=$?" >> $T
  timeout 150 $SAN --tool memcheck --show-backtrace device $Q --gtest_filter="$F" > /tmp/c2/$n-memcheck.log 2>&1; echo "$F memcheck rc=$?" >> $T
  grep -m3 -B2 -A12 "Invalid\|Error\|error" /tmp/c2/$n-memcheck.log | head -40 >> $T
done
tar czf $OUT/logs.tgz -C /tmp/c2 $(cd /tmp/c2 && ls *.log)
date >> $T
