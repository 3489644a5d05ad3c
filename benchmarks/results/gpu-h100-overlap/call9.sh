#!/bin/bash
# Device call 9 (carry .fcl-debs and .gpu-data; 600 s): call 8 still saw the cloth ball's
# candidate search at 0.21 ms in 2 processes of 9 (the scan queued first on a second stream of
# the greatest priority). Now the scan runs on the query's stream, made of the greatest priority,
# and the cells' kernel on a second stream of the least, which waits for the fork event. Twelve
# processes of the default against three of KDET_FCL_CUDA_SELF_OVERLAP=0 (gpu_bench GPU only,
# 20 repeats, the UNC cloth ball and n-body), then test_cuda_query's cells, rounds and joint
# tests.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c9
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
B=build-gpu/benchmarks/gpu_bench
r=0
for round in 1 2 3; do
  for V in "" "" "" "" 0; do
    r=$((r + 1))
    KDET_FCL_CUDA_SELF_OVERLAP=$V timeout 40 $B --no-fcl --no-cpu --repeats 20 \
      --only unc-cloth-ball --only unc-n-body --csv $W/a-$r.csv >> $W/bench.log 2>&1
    echo "round $round (overlap '$V') rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/a-1.csv | sed 's/^/round,overlap,/' > $OUT/runs.csv; fi
    tail -n +2 $W/a-$r.csv | sed "s/^/$round,x$V,/" >> $OUT/runs.csv
  done
done
date >> $T
timeout 120 build-gpu/tests/test_cuda_query \
  --gtest_filter='*SelfPairsWithinALevel*:*IntersectAllHashesTwoMeshes*:*QueriesInRounds*:*WarpScan*:CudaQuery.EveryKnob*' \
  > $W/tests.log 2>&1
echo "tests rc=$?" >> $T; grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/tests.log >> $T
tar czf $OUT/logs.tgz -C $W build.log bench.log tests.log
date >> $T
