#!/bin/bash
# Session 51, call 3 (fresh machine; carry .fcl-debs/root and .gpu-data): after call 2, the
# device-memory test mended (next to nothing, not 0, is left after releaseDeviceMemory) and the
# demo's GPU line for its first query: that test three times, cli_backend again, the demo.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
W=/tmp/s51c
ab_configure $W
ab_targets kdet_fcl kdet test_cuda_query
for r in 1 2 3; do ab_gtest bytes$r 'CudaQuery.DeviceBytesInUse*:CudaQuery.DeviceBytesPerTriangle*'; done
grep -E "Failure|Which is" $W/test-bytes1.txt | head >> $T
(cd build-gpu && ctest -R cli_backend -V) > $W/ctest-cli-backend-v.txt 2>&1
echo "cli_backend rc=$? $(date +%T)" >> $T
grep -E "CUDA devices|demo pair counts|tests passed" $W/ctest-cli-backend-v.txt >> $T
build-gpu/kdet demo --backend cuda --n 100 --frames 3 > $OUT/demo.txt 2>&1
echo "demo rc=$? $(date +%T)" >> $T
tar czf $OUT/out.tgz -C $W .
