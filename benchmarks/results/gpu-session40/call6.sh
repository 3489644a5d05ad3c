#!/bin/bash
# Device call 6 (carry .fcl-debs/root and .gpu-data): the final tree (commitVertices demotes from
# 4 MB only, cpu::kDemoteMinBytes): test_dma_passes, HashedMesh, test_cuda_upload (also with the
# knob at 1: every pass in its cache-leaving form) and test_cuda_query; then phase_probe once.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s40c6
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
cmake --build build-gpu --parallel 16 --target kdet_fcl test_cuda_query test_cuda_upload \
  test_hierarchy test_dma_passes >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
B=build-gpu/tests
timeout 60 $B/test_dma_passes > $W/t-dma.txt 2>&1; echo "test_dma_passes rc=$?" >> $T
timeout 120 $B/test_hierarchy --gtest_filter='HashedMesh.*' > $W/t-hm.txt 2>&1; echo "HashedMesh rc=$?" >> $T
timeout 60 $B/test_cuda_upload > $W/t-upload.txt 2>&1; echo "test_cuda_upload rc=$?" >> $T
KDET_FCL_DMA_PASSES=1 timeout 60 $B/test_cuda_upload > $W/t-upload1.txt 2>&1; echo "test_cuda_upload knob 1 rc=$?" >> $T
timeout 90 $B/test_cuda_query > $W/t-query.txt 2>&1; echo "test_cuda_query rc=$?" >> $T
for f in $W/t-*.txt; do echo "$f: $(tail -n 1 $f)" >> $T; done
date >> $T
tar czf $OUT/out.tgz -C $W .
