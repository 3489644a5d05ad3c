#!/bin/bash
# Device call 1 (carry .fcl-debs and .gpu-data; 600 s): where the cloth ball's frame goes now.
# Builds test_cuda_query (with a print of the cells' test's counts, patched here only) and
# gpu_bench; gpu_bench GPU only on the cloth ball (three processes); ncu's kernel durations of the
# cloth ball (one repeat, every kernel); the crossing sheets' candidates per source under the
# rounds (KDET_FCL_CUDA_ROUND_CANDIDATES unset and 1) with the upper levels' records
# (KDET_FCL_CUDA_UPPER_LEVELS) 0 and 1.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c1
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
# The print (this copy of the tree only).
sed -i 's|^\(        const cuda::QueryProfile p = cuda::lastQueryProfile();\)$|\1\n        std::printf("COUNTS %s: candidates %zu cells %zu rounds %d cell_rounds %d passes %d\\n", what.c_str(), p.candidates, p.cell_candidates, p.rounds, p.cell_rounds, p.passes);|' tests/test_cuda_query.cpp
sed -i "1i #include <cstdio>" tests/test_cuda_query.cpp
grep -c "COUNTS %s" tests/test_cuda_query.cpp >> $T
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_query gpu_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
F='CudaQueryTyped/0.SelfPairsWithinALevel*'
for RC in default 1; do
  for UL in 0 1; do
    if [ $RC = default ]; then unset KDET_FCL_CUDA_ROUND_CANDIDATES; else export KDET_FCL_CUDA_ROUND_CANDIDATES=$RC; fi
    KDET_FCL_CUDA_UPPER_LEVELS=$UL timeout 60 build-gpu/tests/test_cuda_query --gtest_filter="$F" \
      > $W/sheets-$RC-$UL.log 2>&1
    echo "cells test, round candidates $RC, upper levels $UL: rc=$?" >> $T
    echo "== round candidates $RC, upper levels $UL" >> $OUT/sheets.txt
    grep "^COUNTS" $W/sheets-$RC-$UL.log >> $OUT/sheets.txt
  done
done
unset KDET_FCL_CUDA_ROUND_CANDIDATES
date >> $T
B=build-gpu/benchmarks/gpu_bench
for r in 1 2 3; do
  timeout 45 $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --csv $W/bench-$r.csv >> $W/bench.log 2>&1
  echo "bench $r rc=$?" >> $T
  if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,/' > $OUT/bench.csv; fi
  tail -n +2 $W/bench-$r.csv | sed "s/^/$r,/" >> $OUT/bench.csv
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
timeout 240 $NCU --clock-control none \
  --metrics gpu__time_duration.sum,launch__grid_size,launch__registers_per_thread,sm__warps_active.avg.pct_of_peak_sustained_active \
  --csv --print-units base $B --no-fcl --no-cpu --repeats 1 --only unc-cloth-ball > $W/ncu.csv 2> $W/ncu.err
echo "ncu rc=$?" >> $T
cp $W/ncu.csv $OUT/ncu-cloth-ball.csv
python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py $W/ncu.csv > $OUT/kernels.txt 2>&1
date >> $T
tar czf $OUT/logs.tgz -C $W build.log bench.log ncu.err $(cd $W && ls sheets-*.log)
date >> $T
