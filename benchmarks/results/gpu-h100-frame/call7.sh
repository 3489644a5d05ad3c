#!/bin/bash
# Seventh device call (carry .fcl-debs and .gpu-data): the review mend (orient3dSign's fallback
# in one function, no behaviour change). Builds test_cuda_query, runs it whole, and memcheck of
# the plane filter tests.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 TARGETS="test_cuda_query" scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "build (ctest of unbuilt programs fails) rc=$?" >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
timeout 200 build-gpu/tests/test_cuda_query > /tmp/chk/query.log 2>&1
echo "test_cuda_query rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED|SKIPPED) " /tmp/chk/query.log | sort | uniq -c | head >> $T
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 120 $SAN --tool memcheck --error-exitcode 3 build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQuery.PlaneFilter*' > /tmp/chk/memcheck.log 2>&1
echo "memcheck rc=$?" >> $T; tail -2 /tmp/chk/memcheck.log >> $T
tar czf $OUT/logs.tgz -C /tmp/chk check.log query.log memcheck.log
date >> $T
