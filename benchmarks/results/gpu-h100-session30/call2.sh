#!/bin/bash
# Device call 2 (carry .fcl-debs and .gpu-data; 600 s): the grid folded into trianglesKernel's
# last block (KDET_FCL_CUDA_FOLD_GRID, default 1) and the one trip's copy of host results of up
# to k read-back chunks (KDET_FCL_CUDA_ONE_TRIP_COPY, default 1). Builds test_cuda_query and
# gpu_bench; runs all of test_cuda_query; gpu_bench GPU only in three rounds of four settings
# (fold/copy: 1/1, 0/1, 1/2, 1/4), one process each; then a mutant of the fold (the first block
# computes the grid, not the last), whose new test must fail.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c2
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
timeout 240 build-gpu/tests/test_cuda_query > $W/tests.log 2>&1
echo "test_cuda_query rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED|^\[  SKIPPED" $W/tests.log >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for round in 1 2 3; do
  for C in 1/1 0/1 1/2 1/4; do
    r=$((r + 1))
    F=${C%/*}; K=${C#*/}
    KDET_FCL_CUDA_FOLD_GRID=$F KDET_FCL_CUDA_ONE_TRIP_COPY=$K timeout 60 $B --no-fcl --no-cpu \
      --repeats 20 --only unc-cloth-ball --only unc-funnel --only unc-n-body --only cloth-90k \
      --only cloth-1000k --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r (fold $F, copy $K) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,fold,copy,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$F,$K,/" >> $OUT/bench.csv
  done
done
date >> $T
left=$((560 - ($(date +%s) - START)))
echo "left $left s" >> $T
if [ $left -gt 150 ]; then
  cp cuda/cuda_backend.cu $W/cuda_backend.cu.orig
  sed -i 's/last = atomicAdd(&red->blocks_done, 1ull) == gridDim.x - 1ull;/last = atomicAdd(\&red->blocks_done, 1ull) == 0ull;/' cuda/cuda_backend.cu
  grep -c "blocks_done, 1ull) == 0ull;" cuda/cuda_backend.cu >> $T
  cmake --build build-gpu --parallel 16 --target test_cuda_query > $W/build-mut.log 2>&1
  echo "mutant build rc=$?" >> $T
  timeout 90 build-gpu/tests/test_cuda_query --gtest_filter='*TheGridOfTheTrianglesKernelsLastBlock*' > $W/tests-mut.log 2>&1
  echo "mutant tests rc=$? (must be non-zero)" >> $T
  grep -E "^\[  (PASSED|FAILED) " $W/tests-mut.log >> $T; grep -c "Failure" $W/tests-mut.log >> $T
  cp $W/cuda_backend.cu.orig cuda/cuda_backend.cu
fi
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log)
date >> $T
