#!/bin/bash
# Session 51, call 6 (fresh machine; carry .fcl-debs/root and .gpu-data): after the review mend
# (the re-hash graph test's repeated steps through one lambda, the kdet tool's device-memory
# line and its indent): that test and the device-memory test three times, and cli_backend.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
W=/tmp/s51f
ab_configure $W
ab_targets kdet_fcl kdet test_cuda_query
for r in 1 2 3; do ab_gtest mend$r 'CudaQuery.ARehashGraphWhoseBuffersMoved*:CudaQuery.DeviceBytesInUse*'; done
(cd build-gpu && ctest -R cli_backend -V) > $W/cli.txt 2>&1
echo "cli_backend rc=$? $(date +%T)" >> $T
grep -E "demo pair counts|tests passed" $W/cli.txt >> $T
build-gpu/kdet demo --backend cuda --n 50 --frames 2 | tail -2 >> $T
