#!/bin/bash
# Device call 9 (carry .fcl-debs and .gpu-data): the review mend (no behaviour change: the read-back
# chunk in elements through staging::downloadChunkElements, the sort's delivery through runQuery's
# delivery()). Builds the CUDA tests and runs ctest -L cuda (with its 4 KiB-chunk, rounds, tile
# and spans variants of test_cuda_query).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/c9
OUT=/tmp/c9 CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh" \
  scripts/gpu_check.sh > /tmp/c9/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/c9/ctest.log | head -30 >> $T
cp /tmp/c9/ctest.log $OUT/
date >> $T
