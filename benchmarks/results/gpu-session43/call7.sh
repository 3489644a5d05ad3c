#!/bin/bash
# Device call 7 (carry .fcl-debs/root and .gpu-data): the review mend (acquire's test of a copied
# version reduced to the version alone; one helper for the two calls' copies). The whole of
# test_cuda_query, the copy tests under the tile scan, and the CPU test of the pieces.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s43c7
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L:$PWD/build-gpu
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_query test_commit_copy >> $W/build.log 2>&1
echo "build rc=$? $(date +%T)" >> $T
build-gpu/tests/test_commit_copy > $W/test-commit-copy.txt 2>&1
echo "test_commit_copy rc=$? $(date +%T)" >> $T
F='*Cop*:*Commit*:*Knob*'
build-gpu/tests/test_cuda_query > $W/test-cuda-query.txt 2>&1
echo "test_cuda_query rc=$? $(date +%T)" >> $T
KDET_FCL_CUDA_SCAN=tile build-gpu/tests/test_cuda_query --gtest_filter="$F" > $W/test-copy-tile.txt 2>&1
echo "copy tests (tile) rc=$? $(date +%T)" >> $T
date >> $T
cp $W/test-*.txt $OUT/
