#!/bin/bash
# Third device call of gpu-both (carry .fcl-debs and .gpu-data): the counting build's counters
# taken by groups of threads (groupIncrement): build, ctest -L cuda, memcheck of the count test;
# the count forced on and off on the cloth ball, 20k and 1M cloths (two rounds); the whole
# gpu_bench (FCL and the CPU too) for the latest tables; ncu of the counting kernels at 1M.
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
for r in 1 2; do
  for v in 1 0; do
    KDET_FCL_CUDA_COUNT_BUILD=$v timeout 60 $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball-self --only cloth-20k --only cloth-1000k \
      --csv $OUT/ab-$v-$r.csv > $OUT/ab-$v-$r.log 2>&1
    echo "ab count=$v round $r rc=$?" >> $T
  done
done
date >> $T
timeout 200 $B --csv $OUT/full.csv > $OUT/full.log 2>&1
echo "full rc=$?" >> $T
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for v in 1 0; do
  KDET_FCL_CUDA_COUNT_BUILD=$v timeout 45 $NCU --clock-control none --kernel-name regex:'countFill|countCells|scatter|fillKernel|entriesKernel|headsKernel|cellsKernel' \
    -c 24 --metrics gpu__time_duration.sum --csv $B --no-fcl --no-cpu --repeats 1 --only cloth-1000k > $OUT/ncu-$v.csv 2> $OUT/ncu-$v.err
  echo "ncu $v rc=$?" >> $T
done
date >> $T
