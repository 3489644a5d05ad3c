#!/bin/bash
# Device call 5 (carry .fcl-debs and .gpu-data; 600 s): double_probe.cpp (why kdet_bench's kDet
# GPU frames took 3-5x gpu_bench's): the library built, the probe compiled against it and run.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c5
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L:$PWD/build-gpu
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target kdet_fcl >> $W/build.log 2>&1
echo "build rc=$?" >> $T
g++ -O2 -std=c++17 -isystem $D/usr/include -isystem $D/usr/include/x86_64-linux-gnu \
  -I /usr/include/eigen3 -I include -I . -I benchmarks \
  benchmarks/results/gpu-h100-session37/double_probe.cpp benchmarks/bench_scenes.cpp \
  -L build-gpu -L $L -lkdet_fcl -o /tmp/dprobe > $W/probe-build.log 2>&1
echo "probe build rc=$?" >> $T
date >> $T
timeout 300 /tmp/dprobe > $OUT/probe.txt 2> $W/probe.err
echo "probe rc=$?" >> $T
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err 2>/dev/null)
date >> $T
