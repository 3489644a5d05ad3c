#!/bin/bash
# Second device call of gpu-both (carry .fcl-debs and .gpu-data): the counting build by size
# (kCountBuildMaxTriangles): build, ctest -L cuda, memcheck of the count test; a sweep of
# KDET_FCL_CUDA_COUNT_BUILD unset/1/0 over the cloth sizes and the UNC cloth ball (pinned uploads
# on), two rounds; the 10M cloth with the defaults, with the count forced and with both off; ncu
# of the build kernels on the 1M cloth, count against sort. Writes $OUT/out.tgz, $OUT/times.txt.
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
timeout 150 $SAN --tool memcheck build-gpu/tests/test_cuda_query --gtest_filter='CudaQueryTyped/0.RehashesGroup*' > $OUT/memcheck-count.log 2>&1
echo "memcheck count rc=$?" >> $T; tail -2 $OUT/memcheck-count.log >> $T
date >> $T
ONLY="--only unc-cloth-ball --only cloth-20k --only cloth-40k --only cloth-90k --only cloth-200k --only cloth-250k --only cloth-1000k"
for r in 1 2; do
  for v in default 1 0; do
    if [ $v = default ]; then unset KDET_FCL_CUDA_COUNT_BUILD; else export KDET_FCL_CUDA_COUNT_BUILD=$v; fi
    timeout 90 $B --no-fcl --no-cpu --repeats 20 $ONLY --csv $OUT/sweep-$v-$r.csv > $OUT/sweep-$v-$r.log 2>&1
    echo "sweep count=$v round $r rc=$?" >> $T
  done
  unset KDET_FCL_CUDA_COUNT_BUILD
  date >> $T
done
for cp in d 1 00; do
  case $cp in d) E="";; 1) E="KDET_FCL_CUDA_COUNT_BUILD=1";; 00) E="KDET_FCL_CUDA_COUNT_BUILD=0 KDET_FCL_CUDA_PIN_VERTICES=0";; esac
  env $E timeout 100 $B --no-fcl --no-cpu --big --only 10000k --repeats 5 --csv $OUT/big-$cp.csv > $OUT/big-$cp.log 2>&1
  echo "big $cp ($E) rc=$?" >> $T
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for v in 1 0; do
  KDET_FCL_CUDA_COUNT_BUILD=$v timeout 100 $NCU --clock-control none --kernel-name regex:'count|scatter|Scan|triangles|grid|fill|Radix|entries|heads|cells|upper' \
    --metrics gpu__time_duration.sum,dram__bytes.sum,lts__t_sector_hit_rate.pct --csv $B --no-fcl --no-cpu --repeats 1 \
    --only cloth-1000k > $OUT/ncu-$v.csv 2> $OUT/ncu-$v.err
  echo "ncu $v rc=$?" >> $T
done
date >> $T
