#!/bin/bash
# Device call 8 (carry .fcl-debs/root and .gpu-data): 32 rows per task of the cells' pairs
# (KDET_FCL_CUDA_CELL_ROWS=32) on the sparse meshes below the many-cells limit (default 8 rows
# there), now that their cells test spans, against the defaults and a placebo; one form per
# frame, rotated by round (a launch-only knob), host frames and phase 1's device time. The UNC
# n-body takes 32 rows already: there the knob is a placebo too.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s42c8
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
echo "lib rc=$? $(date +%T)" >> $T
P=benchmarks/results/gpu-session42
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 $P/frame_probe.cpp \
  benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath \
  -Wl,--allow-shlib-undefined -o $W/probe > $W/probe-build.log 2>&1
echo "probe build rc=$? $(date +%T)" >> $T
F="base;KDET_FCL_CUDA_CELL_ROWS=32;KDET_FCL_CUDA_TILE=8"
SC="unc-funnel unc-cloth-ball cloth-20k cloth-40k cloth-90k chair unc-n-body"
FORMS="$F" ROUNDS=31 timeout 200 $W/probe $SC > $W/probe-off.txt 2>&1
echo "probe off rc=$? $(date +%T)" >> $T
PROFILE=1 FORMS="$F" ROUNDS=31 timeout 200 $W/probe $SC > $W/probe-on.txt 2>&1
echo "probe on rc=$? $(date +%T)" >> $T
date >> $T
cp $W/probe-*.txt $OUT/
tar czf $OUT/out.tgz -C $W --exclude=probe .
