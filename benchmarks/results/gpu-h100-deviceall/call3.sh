#!/bin/bash
# Third device call (carry .fcl-debs and .gpu-data; 600 s): call 2 again after the test fix
# (a fresh mesh for the kept block): builds every CUDA test and gpu_bench as call 1 did, runs
# ctest -L cuda and the script's sanitizer pass (memcheck and racecheck on a small scene), then
# memcheck of the device-form and kept-result tests.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 SANITIZER=1 TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/chk/ctest.log | head -30 >> $T
cp /tmp/chk/ctest.log $OUT/ctest.log 2>/dev/null
cp /tmp/chk/*san*.log $OUT/ 2>/dev/null; ls /tmp/chk > $OUT/chk-files.txt
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 150 $SAN --tool memcheck build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQueryTyped/0.*OnTheDevice*:CudaQuery.SelfResultOfAnUnchangedMesh*' > $OUT/memcheck.log 2>&1
echo "memcheck rc=$?" >> $T; tail -2 $OUT/memcheck.log >> $T
date >> $T
