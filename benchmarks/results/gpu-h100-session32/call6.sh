#!/bin/bash
# Device call 6 (carry .fcl-debs and .gpu-data; 600 s): the committed tree (warpEntryTriangle
# reflowed after calls 3-5: two shuffles on two lines, comments; no behaviour change). Builds
# test_cuda_warp_search, test_cuda_query and gpu_bench; runs both tests (test_cuda_query also
# with every re-hash a counting build) and the cloth ball's gpu_bench, GPU only.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c6
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_warp_search test_cuda_query gpu_bench \
  >> $W/build.log 2>&1
echo "build rc=$?" >> $T
git log --oneline -1 >> $T 2>&1
timeout 60 build-gpu/tests/test_cuda_warp_search > $W/tests-search.log 2>&1
echo "test_cuda_warp_search rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED|SKIPPED) |^\[  FAILED" $W/tests-search.log >> $T
timeout 200 build-gpu/tests/test_cuda_query > $W/tests-all.log 2>&1
echo "test_cuda_query rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/tests-all.log >> $T
KDET_FCL_CUDA_COUNT_BUILD=1 timeout 200 build-gpu/tests/test_cuda_query > $W/tests-count.log 2>&1
echo "test_cuda_query (KDET_FCL_CUDA_COUNT_BUILD=1) rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/tests-count.log >> $T
timeout 60 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 \
  --only unc-cloth-ball-self --csv $OUT/bench.csv > $W/bench.log 2>&1
echo "bench rc=$?" >> $T
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log)
date >> $T
