#!/bin/bash
# Second device call of the counting order (carry .fcl-debs and .gpu-data; 600 s): segments of
# up to 256 pairs, and only from 4096 pairs by default (call 1: 64 pairs made the cloth ball and
# the joint frames sort, and small pair counts were slower counted). Builds test_cuda_query and
# gpu_bench, runs their ctest -L cuda tests, memcheck of the new test, then gpu_bench on the UNC
# scenes and the 90k, 250k and 1M cloths in four alternating rounds (the default, then
# KDET_FCL_CUDA_COUNT_ORDER=0: the radix sort), then the 10M cloth once each way. At most 8 files
# come back: the rounds' CSVs go into one (bench.csv, with the round and the knob in front).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 TARGETS="test_cuda_query gpu_bench" \
  scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/chk/ctest.log | head -30 >> $T
cp /tmp/chk/ctest.log $OUT/ctest.log 2>/dev/null
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 120 $SAN --tool memcheck build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQueryTyped/0.PairsAreOrderedByCounting*:CudaQueryTyped/0.IntersectAllHashes*' > $OUT/memcheck.log 2>&1
echo "memcheck rc=$?" >> $T; tail -2 $OUT/memcheck.log >> $T
date >> $T
for r in 1 2 3 4; do
  if [ $((r % 2)) = 1 ]; then ORDER=; else ORDER=0; fi
  KDET_FCL_CUDA_COUNT_ORDER=$ORDER timeout 100 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 \
    --only unc --only cloth-90k --only cloth-250k --only cloth-1000k \
    --csv /tmp/chk/bench-$r.csv >> $OUT/bench.log 2>&1
  echo "bench round $r (KDET_FCL_CUDA_COUNT_ORDER='$ORDER') rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/chk/bench-1.csv | sed 's/^/round,count_order,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/chk/bench-$r.csv | sed "s/^/$r,'$ORDER',/" >> $OUT/bench.csv
done
date >> $T
for ORDER in "" 0; do
  KDET_FCL_CUDA_COUNT_ORDER=$ORDER timeout 100 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --big --only 10000k \
    --csv /tmp/chk/big$ORDER.csv >> $OUT/big.log 2>&1
  echo "10M (KDET_FCL_CUDA_COUNT_ORDER='$ORDER') rc=$?" >> $T
  cat /tmp/chk/big$ORDER.csv >> $OUT/big.csv
done
date >> $T
