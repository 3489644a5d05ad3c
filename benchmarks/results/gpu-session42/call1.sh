#!/bin/bash
# Device call 1 (carry .fcl-debs/root and .gpu-data): kdet_bench's frame in frame_probe.cpp,
# the defaults against KDET_FCL_CUDA_SPANS=1 (session 41: faster kernels, slower frames), with
# profiling off (as kdet_bench) and on; then ncu of the n-body pair's inter scan per form with
# ncu's cache flush (its default) and without.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s42c1
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
SC="unc-n-body unc-n-body-pair unc-funnel-pair cloth-20k cloth-200k cloth-1000k"
FORMS="base;KDET_FCL_CUDA_SPANS=1" ROUNDS=9 timeout 150 $W/probe $SC > $W/probe-off.txt 2>&1
echo "probe off rc=$? $(date +%T)" >> $T
PROFILE=1 FORMS="base;KDET_FCL_CUDA_SPANS=1" ROUNDS=9 timeout 150 $W/probe $SC > $W/probe-on.txt 2>&1
echo "probe on rc=$? $(date +%T)" >> $T
FORMS="base;KDET_FCL_CUDA_SPANS=1;KDET_FCL_CUDA_SELF_OVERLAP=0;KDET_FCL_CUDA_SPANS=1+KDET_FCL_CUDA_SELF_OVERLAP=0" \
  ROUNDS=9 timeout 100 $W/probe unc-n-body unc-n-body-pair cloth-200k > $W/probe-overlap.txt 2>&1
echo "probe overlap rc=$? $(date +%T)" >> $T
for cc in all none; do
  for k in 0 1; do
    [ $k = 1 ] && export KDET_FCL_CUDA_SPANS=1
    FORMS=base ROUNDS=3 timeout 60 ncu --clock-control none --cache-control $cc \
      --kernel-name-base demangled --kernel-name regex:'Candidates|CellPairs' \
      --metrics gpu__time_duration.sum --csv --print-units base \
      $W/probe unc-n-body-pair unc-n-body > $W/ncu-$cc-$k.csv 2> $W/ncu-$cc-$k.err
    echo "ncu $cc $k rc=$? $(date +%T)" >> $T
    unset KDET_FCL_CUDA_SPANS
  done
done
date >> $T
cp $W/probe-*.txt $OUT/
tar czf $OUT/out.tgz -C $W --exclude=probe .
