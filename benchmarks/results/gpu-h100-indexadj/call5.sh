#!/bin/bash
# Fifth device call (carry .fcl-debs and .gpu-data; 600 s): the cells' pairs load a partner's
# sub-cell span beside its entry, before the canonical-cell test (KDET_FCL_CUDA_CELL_SPAN_WITH_ENTRY,
# new, default on; gpu-h100-stalls: the kernel stalls on L1TEX data 66 % of its cycles). It ran
# on commit d2a9d41; it measured level and was reverted, so this script no longer applies to main. Builds
# test_cuda_query and gpu_bench; ctest -L cuda of test_cuda_query; memcheck of the cells test
# (float); gpu_bench on the UNC scenes and the 90k, 250k and 1M cloths in six alternating rounds
# (the default, then KDET_FCL_CUDA_CELL_SPAN_WITH_ENTRY=0; one CSV); ncu kernel durations of the
# cloth ball's self query both ways.
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
  --gtest_filter='CudaQueryTyped/0.SelfPairsWithinALevel*' > $OUT/memcheck.log 2>&1
echo "memcheck rc=$?" >> $T; tail -2 $OUT/memcheck.log >> $T
date >> $T
for r in 1 2 3 4 5 6; do
  if [ $((r % 2)) = 1 ]; then K=; else K=0; fi
  KDET_FCL_CUDA_CELL_SPAN_WITH_ENTRY=$K timeout 100 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 \
    --only unc --only cloth-90k --only cloth-250k --only cloth-1000k \
    --csv /tmp/chk/bench-$r.csv >> $OUT/bench.log 2>&1
  echo "bench round $r (KDET_FCL_CUDA_CELL_SPAN_WITH_ENTRY='$K') rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/chk/bench-1.csv | sed 's/^/round,span_with_entry,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/chk/bench-$r.csv | sed "s/^/$r,'$K',/" >> $OUT/bench.csv
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for K in "" 0; do
  KDET_FCL_CUDA_CELL_SPAN_WITH_ENTRY=$K timeout 120 $NCU --clock-control none --metrics gpu__time_duration.sum --csv --print-units base \
    build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 1 --only unc-cloth-ball-self \
    > /tmp/chk/ncu.csv 2> /tmp/chk/ncu.err
  echo "ncu (KDET_FCL_CUDA_CELL_SPAN_WITH_ENTRY='$K') rc=$?" >> $T
  { echo "== KDET_FCL_CUDA_CELL_SPAN_WITH_ENTRY='$K'"; python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py /tmp/chk/ncu.csv; } >> $OUT/kernels.txt 2>&1
  date >> $T
done
