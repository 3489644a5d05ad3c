#!/bin/bash
# Device call 10 (carry .fcl-debs/root and .gpu-data): the review mend (the span-choice test's
# two loops braced, its scan set once per scan): that test and the knob tests on the device.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L:$PWD/build-gpu
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $OUT/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_query >> $OUT/build.log 2>&1
echo "build rc=$? $(date +%T)" >> $T
for env in "" "KDET_FCL_CUDA_SPANS=0" "KDET_FCL_CUDA_SCAN=tile"; do
  env $env build-gpu/tests/test_cuda_query --gtest_filter='*Subcell*:*Knob*:*ManySparse*' \
    > $OUT/test-${env:-default}.txt 2>&1
  echo "test '$env' rc=$? $(tail -1 $OUT/test-${env:-default}.txt)" >> $T
done
date >> $T
