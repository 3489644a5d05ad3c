#!/bin/bash
# Device call 9 (carry .fcl-debs/root and .gpu-data): where the cloth ball's frame goes now on
# this H200 (issue 4): ncu's duration of every kernel of a short gpu_bench run on the cloth ball
# (kDet's GPU and the LBVH; one process, 3 repeats), clocks left alone.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s42c9
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L:$PWD/build-gpu
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target gpu_bench >> $W/build.log 2>&1
echo "build rc=$? $(date +%T)" >> $T
timeout 400 ncu --clock-control none --kernel-name-base demangled \
  --metrics gpu__time_duration.sum --csv --print-units base \
  build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 3 --only unc-cloth-ball-self \
  > $W/ncu.csv 2> $W/ncu.err
echo "ncu rc=$? $(date +%T)" >> $T
gzip -c $W/ncu.csv > $OUT/ncu.csv.gz
tail -5 $W/ncu.err > $OUT/ncu-err-tail.txt
date >> $T
