#!/bin/bash
# Second device call of branch countfill-flag (carry .fcl-debs and .gpu-data): the counting
# build's fill one thread per entry only (the loop over each triangle's cells removed), the size
# rule's knob KDET_FCL_CUDA_COUNT_BUILD_MAX: build, ctest -L cuda, memcheck of the count test;
# the sort against the count (KDET_FCL_CUDA_COUNT_BUILD=0/1) on the UNC cloth ball (self and two
# frames) and the 90k, 200k, 250k and 1M cloths, three rounds, and on the 10M cloth, to set the
# size rule. Writes $OUT/out.tgz and $OUT/times.txt.
set -u
cd "$(dirname "$0")/../../.."
FINAL=$OUT
OUT=$FINAL/w
mkdir -p $OUT
trap 'cp $OUT/times.txt $FINAL/times.txt; tar czf $FINAL/out.tgz -C $FINAL w && rm -rf $FINAL/w' EXIT
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
OUT=$OUT/check CTEST_ALL=0 JOBS=16 TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  scripts/gpu_check.sh > $OUT/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $OUT/check/ctest.log | head -30 >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
date >> $T
B=build-gpu/benchmarks/gpu_bench
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 100 $SAN --tool memcheck build-gpu/tests/test_cuda_query --gtest_filter='CudaQueryTyped/0.RehashesGroup*' > $OUT/memcheck-count.log 2>&1
echo "memcheck count rc=$?" >> $T; tail -2 $OUT/memcheck-count.log >> $T
date >> $T
ONLY="--only unc-cloth-ball --only cloth-90k --only cloth-200k --only cloth-250k --only cloth-1000k"
for r in 1 2 3; do
  for v in 0 1; do
    KDET_FCL_CUDA_COUNT_BUILD=$v timeout 60 $B --no-fcl --no-cpu --repeats 20 $ONLY --csv $OUT/ab-$v-$r.csv > $OUT/ab-$v-$r.log 2>&1
    echo "ab count=$v round $r rc=$?" >> $T
  done
  date >> $T
done
for r in 1 2; do
  for v in 0 1; do
    KDET_FCL_CUDA_COUNT_BUILD=$v timeout 80 $B --no-fcl --no-cpu --big --only 10000k --repeats 5 --csv $OUT/big-$v-$r.csv > $OUT/big-$v-$r.log 2>&1
    echo "big count=$v round $r rc=$?" >> $T
  done
done
date >> $T
