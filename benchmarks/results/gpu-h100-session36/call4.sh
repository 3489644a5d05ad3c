#!/bin/bash
# Device call 4 (carry .fcl-debs and .gpu-data; 600 s): the mended tests (the typed test's 8-byte
# query run twice, so that its rounds are planned; the UNC test pinned to the default round
# limit). test_cuda_query built; every CTest entry of it (ctest -R test_cuda_query: the plain
# run and its variants under knobs, test_cuda_query_rounds among them); then
# readback_probe.cu with call 4's variants.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c4
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_query >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
P=benchmarks/results/gpu-h100-session36/readback_probe.cu
/usr/local/cuda/bin/nvcc -O3 -arch=sm_90 -Xcompiler -fopenmp $P -o /tmp/probe > $W/probe-build.log 2>&1 &
timeout 420 ctest --test-dir build-gpu -R test_cuda_query -V > $W/ctest.log 2>&1
echo "ctest rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*|^[0-9]+: \[ memory   \] KDET" $W/ctest.log | head -40 >> $T
wait
date >> $T
timeout 60 /tmp/probe > $OUT/probe.txt 2>&1
echo "probe rc=$?" >> $T
gzip -c $W/ctest.log > $OUT/ctest.log.gz
date >> $T
