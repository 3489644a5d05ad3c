#!/bin/bash
# Device call 4 (carry .fcl-debs/root and .gpu-data): with the knob check's cost gone, a fair
# audit of the CUDA backend's defaults in kdet_bench's frames: each knob flipped from its
# default, one form per knob value, in blocks (frame_probe.cpp BLOCK=2, the forms rotated by
# round), every pair set checked against the first form's.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s42c4
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
K=KDET_FCL_CUDA_
F="base;${K}TILE=8;${K}UPPER_LEVELS=0;${K}UPPER_LEVELS=1;${K}SELF_OVERLAP=0;${K}SELF_CELLS=0"
F="$F;${K}CELL_ROWS=8;${K}CELL_ROWS=32;${K}CELL_SPANS=0;${K}WARP_LANES=8;${K}WARP_LANES=2"
F="$F;${K}INDEX_ADJACENCY=0;${K}FILTER_DECIDES=0;${K}PLANE_FILTER=0;${K}FILTER_QUEUE=0"
F="$F;${K}COUNT_BUILD=0;${K}COUNT_BUILD=1;${K}REHASH_GRAPH=0;${K}ONE_TRIP_FORECAST=0"
F="$F;${K}PACKED_CANDIDATES=0;${K}PIN_VERTICES=0;${K}MINBLOCKS=12;${K}STAGE_PAIRS=0"
F="$F;${K}FUSED_ORDER=0;${K}WARP_TASKS=0;${K}COUNT_ORDER=0"
SC="unc-cloth-ball unc-cloth-ball-pair unc-funnel unc-funnel-pair unc-n-body unc-n-body-pair cloth-20k cloth-90k cloth-250k cloth-1000k"
FORMS="$F" BLOCK=2 ROUNDS=6 timeout 400 $W/probe $SC > $W/probe-audit.txt 2>&1
echo "probe rc=$? $(date +%T)" >> $T
date >> $T
cp $W/probe-*.txt $OUT/
tar czf $OUT/out.tgz -C $W --exclude=probe .
