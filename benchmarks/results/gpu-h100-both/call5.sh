#!/bin/bash
# Fifth device call (branch countfill-flag; the session's last device minutes): countFillKernel
# without the per-entry poll of need_sync. A/B against main's numbers: the 1M cloth and the cloth
# ball with the count forced, then the count test. Outputs straight in $OUT.
# Session 19: run with timeout_s 185 at the end of the device budget; the build of gpu_bench and
# test_cuda_query took longer than that, so nothing came back. Give it 600 s (build about 4 min).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 TARGETS="gpu_bench test_cuda_query" scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
tail -1 /tmp/chk/build.log >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
for v in 1 0 1 0; do
  KDET_FCL_CUDA_COUNT_BUILD=$v timeout 20 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball-self --only cloth-1000k --csv $OUT/ab-$v.csv >> $OUT/ab.log 2>&1
  echo "ab $v rc=$?" >> $T; grep -h "^unc-cloth-ball-self\|^cloth-1000k" $OUT/ab-$v.csv | cut -d, -f1,6,8 >> $T
done
date >> $T
timeout 40 build-gpu/tests/test_cuda_query --gtest_filter='CudaQueryTyped/*.RehashesGroup*' > $OUT/count-test.log 2>&1
echo "count test rc=$?" >> $T; tail -3 $OUT/count-test.log >> $T
date >> $T
