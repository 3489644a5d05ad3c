#!/bin/bash
# Device call 5 (carry .fcl-debs/root and .gpu-data): the final tree. The host's copy of a mesh's
# build info takes the entry count at the first build's read-back (before, only a re-hash without
# read-back brought it), and the new test checks the default on that first query. Every CUDA test
# (ctest -L cuda: the plain test_cuda_query and its variant runs among them).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s41c5
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L:$PWD/build-gpu
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader > $W/gpu.txt 2>&1
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target kdet_fcl test_cuda_device test_cuda_query \
  test_cuda_bvh test_cuda_upload test_cuda_box_test test_cuda_warp_search test_cuda_predicates \
  >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
(cd build-gpu && timeout 300 ctest -L cuda --output-on-failure > $W/ctest-cuda.txt 2>&1)
echo "ctest -L cuda rc=$?" >> $T
tail -n 4 $W/ctest-cuda.txt >> $T
timeout 60 build-gpu/tests/test_cuda_query --gtest_filter='*ManySparseCells*:*WithinALevel*' \
  > $W/t-cells.txt 2>&1
echo "the cells' tests rc=$?" >> $T
tail -n 3 $W/t-cells.txt >> $T
date >> $T
tar czf $OUT/out.tgz -C $W .
