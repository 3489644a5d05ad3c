#!/bin/bash
# Third device call of the counting order (carry .fcl-debs and .gpu-data; 600 s): the final tree
# after the review mends (comments, and a wider ordering test). Builds every CUDA test program
# and gpu_bench, runs ctest -L cuda and the script's sanitizer pass (memcheck and racecheck on a
# small scene), memcheck of the ordering and joint tests, then gpu_bench on the UNC scenes and
# the 90k, 250k and 1M cloths, two rounds with the defaults (one CSV, the round in front).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 SANITIZER=1 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/chk/ctest.log | head -30 >> $T
cp /tmp/chk/ctest.log $OUT/ctest.log 2>/dev/null
cp /tmp/chk/sanitizer-*.log $OUT/ 2>/dev/null
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 150 $SAN --tool memcheck build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQueryTyped/0.PairsAreOrderedByCounting*:CudaQueryTyped/0.IntersectAllHashes*' > $OUT/memcheck.log 2>&1
echo "memcheck rc=$?" >> $T; tail -2 $OUT/memcheck.log >> $T
date >> $T
for r in 1 2; do
  timeout 100 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 \
    --only unc --only cloth-90k --only cloth-250k --only cloth-1000k \
    --csv /tmp/chk/bench-$r.csv >> $OUT/bench.log 2>&1
  echo "bench round $r rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/chk/bench-1.csv | sed 's/^/round,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/chk/bench-$r.csv | sed "s/^/$r,/" >> $OUT/bench.csv
done
date >> $T
