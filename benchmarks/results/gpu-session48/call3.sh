#!/bin/bash
# Device call 3 of session 48, on call 2's machine (its build-gpu, the tree's library): the
# precision probe (precision_probe.cpp) on the UNC cloth ball and the 90k cloth, phases on.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
W=/tmp/s48c3 && mkdir -p $W && date > $T
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 \
  benchmarks/results/gpu-session48/precision_probe.cpp benchmarks/bench_scenes.cpp -L build-gpu \
  -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath -Wl,--allow-shlib-undefined -o $W/probe \
  > $W/probe-build.log 2>&1
echo "probe build rc=$? $(date +%T)" >> $T
ROUNDS=12 timeout 200 $W/probe unc-cloth-ball cloth-90k > $OUT/probe-on.txt 2>&1
echo "probe on rc=$? $(date +%T)" >> $T
PROFILE=0 ROUNDS=12 timeout 100 $W/probe unc-cloth-ball cloth-90k > $OUT/probe-off.txt 2>&1
echo "probe off rc=$? $(date +%T)" >> $T
cp $W/probe-build.log $OUT/
