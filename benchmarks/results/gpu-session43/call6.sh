#!/bin/bash
# Device call 6 (carry .fcl-debs/root and .gpu-data): why updateVertices' copy is level at 1M
# (call 4: its update 0.16-0.20 ms longer). The frame probe with UPDATE=copy on the 200k-1M
# cloths and the UNC n-body: the default 128 KiB batch against 512 KiB and 1 MiB, the copy off
# and a placebo, twice, and once with profiling; the commit's form with the same batches once.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s43c6
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
P=benchmarks/results/gpu-session42  # the frame probe (UPDATE=copy since session 43)
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 $P/frame_probe.cpp \
  benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath \
  -Wl,--allow-shlib-undefined -o $W/probe > $W/probe-build.log 2>&1
echo "probe build rc=$? $(date +%T)" >> $T
SC="unc-n-body cloth-200k cloth-250k cloth-1000k"
B=KDET_FCL_CUDA_COMMIT_BATCH
F="base;$B=524288;$B=1048576;KDET_FCL_CUDA_COMMIT_COPY=0;KDET_FCL_CUDA_TILE=8"
for r in 1 2; do
  UPDATE=copy FORMS="$F" ROUNDS=13 timeout 200 $W/probe $SC > $W/probe-update$r.txt 2>&1
  echo "probe update $r rc=$? $(date +%T)" >> $T
done
UPDATE=copy PROFILE=1 FORMS="$F" ROUNDS=9 timeout 200 $W/probe $SC > $W/probe-update-on.txt 2>&1
echo "probe update on rc=$? $(date +%T)" >> $T
FORMS="$F" ROUNDS=13 timeout 200 $W/probe $SC > $W/probe-commit.txt 2>&1
echo "probe commit rc=$? $(date +%T)" >> $T
date >> $T
cp $W/probe-*.txt $OUT/
