#!/bin/bash
# Prepared in session 48 for the next device session; not run (carry .fcl-debs/root and
# .gpu-data). Two calls: `next_check.sh check` on a fresh machine (about 9 minutes), then
# `next_check.sh first` (about 3 minutes; on the same machine it reuses the check's build-gpu).
#   1. scripts/gpu_check.sh on the tree: ctest -L cuda (AMeshThatOutgrowsItsHashGetsRoomForItsNext-
#      Frames in its final form, which releases the device's cache first, has not run on a device),
#      memcheck and racecheck (their filter includes that test), gpu_bench on the cloth ball;
#   2. precision_probe.cpp's first pass (FIRST=1 ROUNDS=0 ONLY=double) on the 90k cloth alone in
#      its process, three processes, on the tree and with outgrown.diff: the fallbacks and the
#      frames of a simulation going forward through the cloth's frames.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
. benchmarks/results/gpu-session48/probe_build.sh
if [ "${1:-}" = check ]; then
  rm -rf build-gpu
  ab_check
  exit
fi
date > $T
[ -f build-gpu/libkdet_fcl.so ] || { ab_configure /tmp/s49; ab_targets kdet_fcl; }
W=/tmp/s49
mkdir -p $W
P=benchmarks/results/gpu-session48
first() {
  for i in 1 2 3; do
    FIRST=1 ROUNDS=0 ONLY=double timeout 60 $W/probe cloth-90k 2>&1 | grep -v "^kdet_bench:" \
      > $OUT/first-$1-$i.txt
    echo "first pass $1 $i $(date +%T)" >> $T
  done
}
probe_build
first tree
git apply $P/outgrown.diff >> $T 2>&1
cmake --build build-gpu --parallel 16 --target kdet_fcl >> $W/build.log 2>&1
echo "outgrown.diff: lib rc=$? $(date +%T)" >> $T
first without
git apply -R $P/outgrown.diff
cmake --build build-gpu --parallel 16 --target kdet_fcl >> $W/build.log 2>&1
echo "tree again: lib rc=$? $(date +%T)" >> $T
