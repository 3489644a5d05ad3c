#!/bin/bash
# The planned check of branch count-build (one device call; needs .fcl-debs, .gpu-data carried): build, ctest -L cuda, memcheck on the new test, A/B of the counting build, ncu of the build kernels.
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
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
B=build-gpu/benchmarks/gpu_bench
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 240 $SAN --tool memcheck build-gpu/tests/test_cuda_query --gtest_filter='CudaQueryTyped/0.RehashesGroup*' > $OUT/memcheck.log 2>&1
echo "memcheck rc=$?" >> $T; tail -3 $OUT/memcheck.log >> $T
date >> $T
for r in 1 2; do
  for v in 1 0; do
    KDET_FCL_CUDA_COUNT_BUILD=$v $B --no-fcl --no-cpu --repeats 20 --only unc --only cloth-90k --only cloth-250k --only cloth-1000k \
      --csv $OUT/ab-$v-$r.csv > $OUT/ab-$v-$r.log 2>&1
    echo "ab $v $r rc=$?" >> $T
  done
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for v in 1 0; do
  KDET_FCL_CUDA_COUNT_BUILD=$v timeout 100 $NCU --clock-control none --kernel-name regex:'count|scatter|Scan|triangles|grid|fill|Radix|entries|heads|cells|upper' \
    --metrics gpu__time_duration.sum --csv $B --no-fcl --no-cpu --repeats 2 \
    --only unc-cloth-ball-self --only cloth-1000k > $OUT/ncu-$v.csv 2> $OUT/ncu-$v.err
  echo "ncu $v rc=$?" >> $T
done
date >> $T
