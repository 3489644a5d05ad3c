#!/bin/bash
# Device call 4 (carry .fcl-debs/root and .gpu-data): the warp-wide scans that test spans at 7 or
# 6 blocks per SM (experiment KDET_FCL_CUDA_WARP_BLOCKS: at most 72 or 80 registers, against 64;
# the double self scan then spills nothing, the float one less) against the defaults and a placebo
# knob: the frame probe (session 42's), profiling off and on; gpu_bench's cloth ball, two
# processes per form in turn. No test run (the knob only changes the kernels' register cap).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
nproc >> $T
nvidia-smi --query-gpu=name,memory.total --format=csv >> $T 2>&1
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s44c4
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
(cmake --build build-gpu --parallel 12 --target gpu_bench > $W/build2.log 2>&1
 echo "bench+test build rc=$? $(date +%T)" >> $T) &
BG=$!
P=benchmarks/results/gpu-session42  # the frame probe of session 42, unchanged
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 $P/frame_probe.cpp \
  benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath \
  -Wl,--allow-shlib-undefined -o $W/probe > $W/probe-build.log 2>&1
echo "probe build rc=$? $(date +%T)" >> $T
SC="unc-cloth-ball unc-funnel unc-n-body cloth-20k cloth-90k cloth-250k cloth-1000k chair"
F="base;KDET_FCL_CUDA_WARP_BLOCKS=7;KDET_FCL_CUDA_WARP_BLOCKS=6;KDET_FCL_CUDA_TILE=8"
FORMS="$F" ROUNDS=13 timeout 150 $W/probe $SC > $W/probe-off.txt 2>&1
echo "probe off rc=$? $(date +%T)" >> $T
PROFILE=1 FORMS="$F" ROUNDS=13 timeout 150 $W/probe $SC > $W/probe-on.txt 2>&1
echo "probe on rc=$? $(date +%T)" >> $T
wait $BG
B=build-gpu/benchmarks/gpu_bench
for r in 1 2; do
  for w in 8 7 6; do
    KDET_FCL_CUDA_WARP_BLOCKS=$w timeout 60 $B --data $KDET_FCL_DATA_DIR --no-fcl --no-cpu \
      --repeats 20 --only unc-cloth-ball --csv $W/ball-$w-$r.csv >> $W/ball.log 2>&1
    echo "cloth ball blocks=$w $r rc=$? $(date +%T)" >> $T
    if [ ! -f $OUT/ball.csv ]; then head -1 $W/ball-$w-$r.csv | sed 's/^/blocks,process,/' > $OUT/ball.csv; fi
    tail -n +2 $W/ball-$w-$r.csv | sed "s/^/$w,$r,/" >> $OUT/ball.csv
  done
done
date >> $T
cp $W/probe-*.txt $OUT/
tar czf $OUT/out.tgz -C $W --exclude=probe --exclude='*.csv' .
