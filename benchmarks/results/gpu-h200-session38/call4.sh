#!/bin/bash
# Device call 4 (carry .fcl-debs/root and .gpu-data): the FCL entry points' deformation path
# (vertices only, through commitVertices) with a device: test_fcl_collide (its CUDA backend test
# deforms a plain model in place and compares each frame's GPU contacts with the CPU's) and
# test_fcl_mesh, each as one process.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s38c4
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
nvidia-smi --query-gpu=name --format=csv,noheader > $W/gpu.txt 2>&1
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_fcl_collide test_fcl_mesh >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
for t in test_fcl_collide test_fcl_mesh; do
  timeout 120 build-gpu/tests/$t > $W/$t.log 2>&1
  echo "$t rc=$? $(grep -E '^\[  (PASSED|FAILED) ' $W/$t.log | tr '\n' ' ')" >> $T
done
date >> $T
tar czf $OUT/logs.tgz -C $W .
