#!/bin/bash
# Device call 2 (carry .fcl-debs/root and .gpu-data): the batch of the commit's copy
# (KDET_FCL_CUDA_COMMIT_BATCH) measured by the frame probe: 1 MiB (the default of call 1),
# 256, 128 and 64 KiB, against no copy and a placebo knob; the commit tests with the rewritten
# expectations, under the defaults and the tile scan.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s43c2
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
(cmake --build build-gpu --parallel 12 --target test_cuda_query test_commit_copy > $W/build2.log 2>&1; echo "test build rc=$? $(date +%T)" >> $T) &
BG=$!
P=benchmarks/results/gpu-session42  # the frame probe of session 42, unchanged
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 $P/frame_probe.cpp \
  benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath \
  -Wl,--allow-shlib-undefined -o $W/probe > $W/probe-build.log 2>&1
echo "probe build rc=$? $(date +%T)" >> $T
SC="unc-cloth-ball unc-funnel unc-n-body cloth-20k cloth-40k cloth-90k cloth-200k cloth-250k cloth-1000k nbody-181k chair"
B=KDET_FCL_CUDA_COMMIT_BATCH
F="base;$B=262144;$B=131072;$B=65536;KDET_FCL_CUDA_COMMIT_COPY=0;KDET_FCL_CUDA_TILE=8"
FORMS="$F" ROUNDS=13 timeout 240 $W/probe $SC > $W/probe-a.txt 2>&1
echo "probe a rc=$? $(date +%T)" >> $T
FORMS="$F" ROUNDS=13 timeout 240 $W/probe $SC > $W/probe-b.txt 2>&1
echo "probe b rc=$? $(date +%T)" >> $T
wait $BG
build-gpu/tests/test_commit_copy > $W/test-commit-copy.txt 2>&1
echo "test_commit_copy rc=$? $(date +%T)" >> $T
build-gpu/tests/test_cuda_query --gtest_filter='*Commit*:*Knob*' > $W/test-commit.txt 2>&1
echo "commit tests rc=$? $(date +%T)" >> $T
KDET_FCL_CUDA_SCAN=tile build-gpu/tests/test_cuda_query --gtest_filter='*Commit*' > $W/test-commit-tile.txt 2>&1
echo "commit tests (tile) rc=$? $(date +%T)" >> $T
KDET_FCL_CUDA_COMMIT_BATCH=65536 build-gpu/tests/test_cuda_query --gtest_filter='*Commit*' > $W/test-commit-64k.txt 2>&1
echo "commit tests (64 KiB) rc=$? $(date +%T)" >> $T
date >> $T
cp $W/probe-a.txt $W/probe-b.txt $OUT/
tar czf $OUT/out.tgz -C $W --exclude=probe .
