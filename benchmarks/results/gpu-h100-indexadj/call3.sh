#!/bin/bash
# Third device call (carry .fcl-debs and .gpu-data; 600 s): the tree after calls 1 and 2, with
# the coordinate check taken out of the plane filter again (call 2's ncu: +14 us there; the
# self exact kernel drops those pairs anyway) and segments of up to 1024 pairs counted by
# default (call 2's A/B). Builds every CUDA test program and gpu_bench; ctest -L cuda and the
# script's sanitizer pass (memcheck and racecheck on a small scene); memcheck of the adjacency
# and ordering tests; gpu_bench on the UNC scenes and the 90k, 250k and 1M cloths in four
# alternating rounds: the default, then the tree before this session by its knobs
# (KDET_FCL_CUDA_SIZE_BY_LEVEL=0 KDET_FCL_CUDA_INDEX_ADJACENCY=0
# KDET_FCL_CUDA_COUNT_ORDER_SEGMENT=256); then the 10M cloth once each way.
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
cat /tmp/chk/sanitizer-*.log > $OUT/sanitizer.log 2>/dev/null
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 150 $SAN --tool memcheck build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQueryTyped/0.AdjacencyByIndex*:CudaQueryTyped/0.PairsAreOrderedByCounting*' > $OUT/memcheck.log 2>&1
echo "memcheck rc=$?" >> $T; tail -2 $OUT/memcheck.log >> $T
date >> $T
OLD="SIZE_BY_LEVEL=0 INDEX_ADJACENCY=0 COUNT_ORDER_SEGMENT=256"
for r in 1 2 3 4; do
  if [ $((r % 2)) = 1 ]; then C=""; else C=$OLD; fi
  ENVS=""
  for kv in $C; do ENVS="$ENVS KDET_FCL_CUDA_$kv"; done
  env $ENVS timeout 100 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 \
    --only unc --only cloth-90k --only cloth-250k --only cloth-1000k \
    --csv /tmp/chk/bench-$r.csv >> $OUT/bench.log 2>&1
  echo "bench round $r ('$C') rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/chk/bench-1.csv | sed 's/^/round,config,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/chk/bench-$r.csv | sed "s/^/$r,'$C',/" >> $OUT/bench.csv
done
date >> $T
for C in "" "$OLD"; do
  ENVS=""
  for kv in $C; do ENVS="$ENVS KDET_FCL_CUDA_$kv"; done
  env $ENVS timeout 100 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --big --only 10000k \
    --csv /tmp/chk/big.csv >> $OUT/bench.log 2>&1
  echo "10M ('$C') rc=$?" >> $T
  tail -n +2 /tmp/chk/big.csv | sed "s/^/big,'$C',/" >> $OUT/bench.csv
done
date >> $T
