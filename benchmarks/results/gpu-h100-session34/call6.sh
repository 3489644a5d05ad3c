#!/bin/bash
# Device call 6 (no carry needed; 300 s): the new SpreadItemsAreEachTakenOnceAndFewItemsOnePerWarp
# test of test_cuda_warp_search, compiled directly with nvcc, and a mutant of spreadIndex (the
# stride at 16 lanes' worth instead of 32: items left out) that it must fail.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
mkdir -p /tmp/m6 && cp -r cuda include tests /tmp/m6/
sed -i 's/return {warp + warps \* (threadIdx.x \& 31u), warps \* 32};/return {warp + warps * (threadIdx.x \& 31u), warps * 16};/' /tmp/m6/cuda/device_hash.cuh
grep -c "warps \* 16}" /tmp/m6/cuda/device_hash.cuh >> $T
for t in new m6; do
  case $t in new) R=.;; *) R=/tmp/m6;; esac
  /usr/local/cuda/bin/nvcc -std=c++17 --generate-code=arch=compute_90,code=sm_90 -fmad=false \
    -I$R -I$R/include -I$R/tests $R/tests/test_cuda_warp_search.cu -lgtest -lgtest_main \
    -o /tmp/ws-$t > $OUT/build-$t.log 2>&1
  echo "build $t rc=$?" >> $T
  timeout 60 /tmp/ws-$t > $OUT/run-$t.log 2>&1
  echo "run $t rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $OUT/run-$t.log | head -6 >> $T
done
date >> $T
