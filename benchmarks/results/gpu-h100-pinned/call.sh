#!/bin/bash
# The planned check of branch pinned-upload (one device call; carry .fcl-debs and .gpu-data):
# build, ctest -L cuda, memcheck on the new tests, A/B of KDET_FCL_CUDA_PIN_VERTICES (both kDet
# and the LBVH baseline follow it), the 10M cloth once each way. Writes $OUT/out.tgz, $OUT/times.txt.
set -u
cd "$(dirname "$0")/../../.."
FINAL=$OUT
OUT=$FINAL/w
mkdir -p $OUT
trap 'cp $OUT/times.txt $FINAL/times.txt; tar czf $FINAL/out.tgz -C $FINAL w && rm -rf $FINAL/w' EXIT
T=$OUT/times.txt
date > $T
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
timeout 200 $SAN --tool memcheck build-gpu/tests/test_cuda_query --gtest_filter='CudaQuery.LargeVertexArrays*' > $OUT/memcheck-query.log 2>&1
echo "memcheck query rc=$?" >> $T; tail -2 $OUT/memcheck-query.log >> $T
timeout 120 $SAN --tool memcheck build-gpu/tests/test_cuda_upload --gtest_filter='PinnedUpload.*' > $OUT/memcheck-upload.log 2>&1
echo "memcheck upload rc=$?" >> $T; tail -2 $OUT/memcheck-upload.log >> $T
date >> $T
for r in 1 2; do
  for v in 1 0; do
    KDET_FCL_CUDA_PIN_VERTICES=$v timeout 200 $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --only cloth-250k --only cloth-1000k \
      --csv $OUT/ab-$v-$r.csv > $OUT/ab-$v-$r.log 2>&1
    echo "ab $v $r rc=$?" >> $T
  done
done
date >> $T
for v in 1 0; do
  KDET_FCL_CUDA_PIN_VERTICES=$v timeout 150 $B --no-fcl --no-cpu --big --only 10000k --repeats 3 \
    --csv $OUT/big-$v.csv > $OUT/big-$v.log 2>&1
  echo "big $v rc=$?" >> $T
done
date >> $T
