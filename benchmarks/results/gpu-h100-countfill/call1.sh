#!/bin/bash
# First device call of branch countfill-flag (tree e87af53, the only one with the A/B knob
# KDET_FCL_CUDA_COUNT_FILL; carry .fcl-debs and .gpu-data): build, ctest -L cuda
# (also the first device run of main's 82c8047, which the branch is on); the CUDA query tests with
# the counting build's fill one thread per entry (KDET_FCL_CUDA_COUNT_FILL=1) and memcheck of the
# count test so; an A/B of the build: the sort, the count per triangle (countFillKernel, no
# per-entry need_sync poll) and the count per entry (countEntriesKernel), on the UNC cloth ball
# and the 90k, 250k and 1M cloths, two rounds; ncu durations of the build kernels at 1M.
# Writes $OUT/out.tgz and $OUT/times.txt.
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
KDET_FCL_CUDA_COUNT_FILL=1 timeout 150 build-gpu/tests/test_cuda_query > $OUT/query-entry.log 2>&1
echo "test_cuda_query, fill per entry rc=$?" >> $T; tail -3 $OUT/query-entry.log >> $T
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
KDET_FCL_CUDA_COUNT_FILL=1 timeout 100 $SAN --tool memcheck build-gpu/tests/test_cuda_query --gtest_filter='CudaQueryTyped/0.RehashesGroup*' > $OUT/memcheck-entry.log 2>&1
echo "memcheck count per entry rc=$?" >> $T; tail -2 $OUT/memcheck-entry.log >> $T
date >> $T
ONLY="--only unc-cloth-ball --only cloth-90k --only cloth-250k --only cloth-1000k"
for r in 1 2; do
  for v in sort loop entry; do
    case $v in sort) E="KDET_FCL_CUDA_COUNT_BUILD=0";; loop) E="KDET_FCL_CUDA_COUNT_BUILD=1 KDET_FCL_CUDA_COUNT_FILL=0";;
                entry) E="KDET_FCL_CUDA_COUNT_BUILD=1 KDET_FCL_CUDA_COUNT_FILL=1";; esac
    env $E timeout 60 $B --no-fcl --no-cpu --repeats 20 $ONLY --csv $OUT/ab-$v-$r.csv > $OUT/ab-$v-$r.log 2>&1
    echo "ab $v ($E) round $r rc=$?" >> $T
  done
  date >> $T
done
env KDET_FCL_CUDA_COUNT_FILL=1 timeout 100 $B --no-fcl --no-cpu --big --only 10000k --repeats 5 --csv $OUT/big-entry.csv > $OUT/big-entry.log 2>&1
echo "big, count forced per entry rc=$?" >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for v in loop entry; do
  KDET_FCL_CUDA_COUNT_BUILD=1 KDET_FCL_CUDA_COUNT_FILL=$([ $v = entry ] && echo 1 || echo 0) timeout 45 $NCU --clock-control none \
    --kernel-name regex:'countFill|countEntries|countCells|scatter|fillKernel|entriesKernel|headsKernel|cellsKernel' \
    -c 24 --metrics gpu__time_duration.sum --csv $B --no-fcl --no-cpu --repeats 1 --only cloth-1000k > $OUT/ncu-$v.csv 2> $OUT/ncu-$v.err
  echo "ncu $v rc=$?" >> $T
done
date >> $T
