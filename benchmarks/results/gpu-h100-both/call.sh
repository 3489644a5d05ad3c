#!/bin/bash
# The device check of count-build and pinned-upload merged (branch gpu-both; carry .fcl-debs and
# .gpu-data): build, ctest -L cuda, memcheck on the new tests, A/B of KDET_FCL_CUDA_COUNT_BUILD x
# KDET_FCL_CUDA_PIN_VERTICES on the cloth ball, 250k and 1M (two rounds), the 10M cloth with both
# on and both off. Writes $OUT/out.tgz and $OUT/times.txt.
set -u
cd "$(dirname "$0")/../../.."
FINAL=$OUT
OUT=$FINAL/w
mkdir -p $OUT
trap 'cp $OUT/times.txt $FINAL/times.txt; tar czf $FINAL/out.tgz -C $FINAL w && rm -rf $FINAL/w' EXIT
T=$OUT/times.txt
date > $T
git log --oneline -1 >> $T 2>/dev/null
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
OUT=$OUT/check CTEST_ALL=0 JOBS=16 TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh test_hierarchy gpu_bench" \
  scripts/gpu_check.sh > $OUT/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $OUT/check/ctest.log | head -30 >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
build-gpu/tests/test_hierarchy --gtest_filter='HashedMesh.*' > $OUT/hierarchy.log 2>&1
echo "test_hierarchy HashedMesh rc=$?" >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 150 $SAN --tool memcheck build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQuery.LargeVertexArrays*:CudaQueryTyped/0.RehashesGroup*:CudaQuery.AQueryUnderABadKnob*' > $OUT/memcheck-query.log 2>&1
echo "memcheck query rc=$?" >> $T; tail -2 $OUT/memcheck-query.log >> $T
timeout 60 $SAN --tool memcheck build-gpu/tests/test_cuda_upload --gtest_filter='PinnedUpload.*' > $OUT/memcheck-upload.log 2>&1
echo "memcheck upload rc=$?" >> $T; tail -2 $OUT/memcheck-upload.log >> $T
date >> $T
for r in 1 2; do
  for cp in 11 00 10 01; do
    KDET_FCL_CUDA_COUNT_BUILD=${cp:0:1} KDET_FCL_CUDA_PIN_VERTICES=${cp:1:1} timeout 90 $B --no-fcl --no-cpu --repeats 20 \
      --only unc-cloth-ball --only cloth-250k --only cloth-1000k --csv $OUT/ab-$cp-$r.csv > $OUT/ab-$cp-$r.log 2>&1
    echo "ab count,pin=$cp round $r rc=$?" >> $T
  done
  date >> $T
done
for cp in 11 00; do
  KDET_FCL_CUDA_COUNT_BUILD=${cp:0:1} KDET_FCL_CUDA_PIN_VERTICES=${cp:1:1} timeout 100 $B --no-fcl --no-cpu --big --only 10000k --repeats 3 \
    --csv $OUT/big-$cp.csv > $OUT/big-$cp.log 2>&1
  echo "big count,pin=$cp rc=$?" >> $T
done
date >> $T
