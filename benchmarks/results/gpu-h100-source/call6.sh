#!/bin/bash
# Sixth device call (carry .fcl-debs and .gpu-data; 600 s): the review mend after call 5 (no
# behaviour change: the segment count shared by emitPair and stagePair, the profile's
# fixed_cells from the device's own rule, a level's cell count taken once per step). Builds
# every CUDA test program; ctest -L cuda and the script's sanitizer pass.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 SANITIZER=1 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh" \
  scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/chk/ctest.log | head -30 >> $T
grep -h "ERROR SUMMARY\|RACECHECK SUMMARY" /tmp/chk/sanitizer-*.log >> $T 2>/dev/null
tar czf $OUT/logs.tgz -C /tmp/chk check.log ctest.log $(cd /tmp/chk && ls sanitizer-*.log 2>/dev/null)
date >> $T
