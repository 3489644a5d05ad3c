#!/bin/bash
# Device call 3 (carry .fcl-debs and .gpu-data; 600 s): the full gpu_bench run with every peer
# in one process (--big --repeats 10), after building gpu_bench and test_cuda_query and running
# the two tests whose expectations of the overlap failed in call 2 under
# KDET_FCL_CUDA_ROUND_CANDIDATES=1 (the stages' rounds run the kernels apart; mended), with and
# without that limit.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c3
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target gpu_bench test_cuda_query >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
for lim in "" 1; do
  KDET_FCL_CUDA_ROUND_CANDIDATES=$lim timeout 60 build-gpu/tests/test_cuda_query \
    --gtest_filter='*SelfPairsWithinALevel*:*IntersectAllHashesTwoMeshes*:*QueriesInRounds*' \
    > $W/tests-$lim.log 2>&1
  echo "tests (round candidates '$lim') rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/tests-$lim.log >> $T
done
date >> $T
left=$((590 - ($(date +%s) - START)))
timeout $left build-gpu/benchmarks/gpu_bench --big --repeats 10 --csv $OUT/gpu_bench.csv \
  --json $OUT/gpu_bench.json --md $OUT/gpu_bench.md > $W/gpu_bench.log 2>&1
echo "full run rc=$?" >> $T
tar czf $OUT/logs.tgz -C $W build.log gpu_bench.log $(cd $W && ls tests-*.log)
date >> $T
