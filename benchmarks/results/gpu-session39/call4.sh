#!/bin/bash
# Device call 4 (carry .fcl-debs/root and .gpu-data; cold machine): commit_probe.cpp. Does the
# number of threads of the commit's check change the query that follows (the 1M and 250k cloths,
# double)? The library of the final tree with CUDA, then the probe, twice.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s39c4
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
cmake --build build-gpu --parallel 16 --target kdet_fcl >> $W/build.log 2>&1
echo "build rc=$?" >> $T
g++ -O2 -std=c++17 -I include -I src -I . -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 \
  benchmarks/results/gpu-session39/commit_probe.cpp benchmarks/bench_scenes.cpp \
  -L build-gpu -lkdet_fcl -L$L -lfcl -o $W/probe >> $W/build.log 2>&1
echo "probe build rc=$?" >> $T
date >> $T
for r in 1 2; do
  timeout 150 $W/probe > $W/probe$r.txt 2>&1
  echo "probe $r rc=$?" >> $T
  grep threads $W/probe$r.txt >> $T
done
date >> $T
tar czf $OUT/out.tgz -C $W --exclude=probe .
