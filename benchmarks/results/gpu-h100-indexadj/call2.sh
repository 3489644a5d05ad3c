#!/bin/bash
# Second device call (carry .fcl-debs and .gpu-data; 600 s): the tree after call 1 plus the
# counting order's segment limit as a knob (KDET_FCL_CUDA_COUNT_ORDER_SEGMENT). Builds every
# CUDA test program and gpu_bench and runs ctest -L cuda; memcheck of the ordering test; then
# gpu_bench on the UNC scenes and the 90k, 250k and 1M cloths in six alternating rounds of
# segments of at most 256 (the default), 1024 and 4096 pairs (one CSV, round and limit in
# front); then ncu kernel durations of the cloth ball's self query with the default and with
# KDET_FCL_CUDA_SIZE_BY_LEVEL=0 KDET_FCL_CUDA_INDEX_ADJACENCY=0 (the tree before this session),
# summed per frame on the device by gpu-h100-profile's kernels_per_frame.py (the call ran a
# byte-identical copy in this folder, since removed).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/chk/ctest.log | head -30 >> $T
cp /tmp/chk/ctest.log $OUT/ctest.log 2>/dev/null
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 120 $SAN --tool memcheck build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQueryTyped/0.PairsAreOrderedByCounting*' > $OUT/memcheck.log 2>&1
echo "memcheck rc=$?" >> $T; tail -2 $OUT/memcheck.log >> $T
date >> $T
SEGS=(256 1024 4096)
for r in 1 2 3 4 5 6; do
  G=${SEGS[$(( (r - 1) % 3 ))]}
  KDET_FCL_CUDA_COUNT_ORDER_SEGMENT=$G timeout 100 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 \
    --only unc --only cloth-90k --only cloth-250k --only cloth-1000k \
    --csv /tmp/chk/bench-$r.csv >> $OUT/bench.log 2>&1
  echo "bench round $r (segment $G) rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/chk/bench-1.csv | sed 's/^/round,segment,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/chk/bench-$r.csv | sed "s/^/$r,$G,/" >> $OUT/bench.csv
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for C in new old; do
  if [ $C = old ]; then export KDET_FCL_CUDA_SIZE_BY_LEVEL=0 KDET_FCL_CUDA_INDEX_ADJACENCY=0; fi
  timeout 120 $NCU --clock-control none --metrics gpu__time_duration.sum --csv --print-units base \
    build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 1 --only unc-cloth-ball-self \
    > /tmp/chk/ncu-$C.csv 2> /tmp/chk/ncu-$C.err
  echo "ncu $C rc=$?" >> $T
  { echo "== $C"; python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py /tmp/chk/ncu-$C.csv; } >> $OUT/kernels.txt 2>&1
  date >> $T
done
