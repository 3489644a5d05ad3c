#!/bin/bash
# Device call 1 (carry .fcl-debs and .gpu-data; 600 s): a self query's cells' kernel beside the
# scan of the coarser levels, on a second stream (KDET_FCL_CUDA_SELF_OVERLAP, default 0 in this
# tree), and the cells' share of the candidates counted by the cells' kernel itself (no
# addCountKernel). Builds test_cuda_query and gpu_bench (cmake as scripts/gpu_check.sh); runs
# the tests that cover it, the knob tests and then all of test_cuda_query; gpu_bench (GPU only)
# in six rounds alternating the knob (0, 1) on the scenes whose self queries take the cells'
# pairs; ncu's durations of the cloth ball's query kernels with the knob at 0 and 1.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c1
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_query gpu_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
timeout 150 build-gpu/tests/test_cuda_query \
  --gtest_filter='*SelfPairsWithinALevel*:*QueriesInRounds*:*IntersectAllHashesTwoMeshes*:CudaQuery.EveryKnob*:CudaQuery.AQueryUnderABadKnob*' \
  > $W/tests.log 2>&1
echo "tests rc=$?" >> $T; grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/tests.log >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for R in 0 1 0 1 0 1; do
  r=$((r + 1))
  KDET_FCL_CUDA_SELF_OVERLAP=$R timeout 45 $B --no-fcl --no-cpu --repeats 20 \
    --only unc-cloth-ball --only unc-n-body --only cloth-200k --only cloth-250k \
    --only cloth-1000k --csv $W/bench-$r.csv >> $W/bench.log 2>&1
  echo "bench round $r (overlap $R) rc=$?" >> $T
  if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,overlap,/' > $OUT/bench.csv; fi
  tail -n +2 $W/bench-$r.csv | sed "s/^/$r,$R,/" >> $OUT/bench.csv
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for R in 0 1; do
  KDET_FCL_CUDA_SELF_OVERLAP=$R timeout 45 $NCU --clock-control none \
    --metrics gpu__time_duration.sum,launch__grid_size --csv --print-units base \
    $B --no-fcl --no-cpu --repeats 2 --only unc-cloth-ball > $W/ncu-$R.csv 2> $W/ncu-$R.err
  echo "ncu cloth ball overlap $R rc=$?" >> $T
  echo "== cloth ball, overlap $R" >> $OUT/kernels.txt
  python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py $W/ncu-$R.csv >> $OUT/kernels.txt 2>&1
done
date >> $T
left=$((585 - ($(date +%s) - START)))
if [ $left -gt 60 ]; then
  timeout $left build-gpu/tests/test_cuda_query > $W/all-tests.log 2>&1
  echo "all of test_cuda_query rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/all-tests.log >> $T
fi
tar czf $OUT/logs.tgz -C $W build.log tests.log bench.log $(cd $W && ls all-tests.log *.err 2>/dev/null)
date >> $T
