#!/bin/bash
# Fourth device call (branch device-pairs; the session's last ~520 s of device time; carry
# .fcl-debs and .gpu-data): intersectSelfOnDevice / intersectMeshesOnDevice. Builds test_cuda_query
# and gpu_bench only (ctest -L cuda then also lists the CUDA tests not built as failed); runs the
# CUDA query tests in all their ctest variants, gpu_bench on the cloth ball and the 90k, 250k and
# 1M cloths (kdet_device_ms: the same frames with the pairs left on the device), then memcheck
# of the new test. Files go straight to $OUT as they are made (a cut-off call keeps them).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 TARGETS="test_cuda_query gpu_bench" scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$? (the CUDA tests not built fail by design)" >> $T
grep -E "Test +#[0-9]+: |tests passed|tests failed" /tmp/chk/ctest.log | head -30 >> $T
cp /tmp/chk/ctest.log $OUT/ctest.log 2>/dev/null
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
timeout 90 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --only cloth-90k \
  --only cloth-250k --only cloth-1000k --csv $OUT/bench.csv > $OUT/bench.log 2>&1
echo "bench rc=$?" >> $T
date >> $T
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 90 $SAN --tool memcheck build-gpu/tests/test_cuda_query --gtest_filter='CudaQueryTyped/0.PairsOnTheDevice*' > $OUT/memcheck.log 2>&1
echo "memcheck rc=$?" >> $T; tail -2 $OUT/memcheck.log >> $T
date >> $T
