#!/bin/bash
# Device call 7 (carry .fcl-debs; 600 s): the review mend f3d43d8 (the one trip's setting read
# once; host code only). test_cuda_query and test_cuda_upload whole.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
W=/tmp/c7
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_query test_cuda_upload >> $W/build.log 2>&1
echo "build rc=$?" >> $T
for t in test_cuda_query test_cuda_upload; do
  timeout 200 build-gpu/tests/$t > $W/$t.log 2>&1
  echo "$t rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/$t.log | head -10 >> $T
done
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log)
date >> $T
