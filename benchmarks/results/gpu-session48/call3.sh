#!/bin/bash
# Device call 3 of session 48, on call 2's machine (its build-gpu, the tree's library): the
# precision probe (precision_probe.cpp) on the UNC cloth ball and the 90k cloth, phases on.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
. benchmarks/results/gpu-session48/probe_build.sh  # (the run had its command inline)
W=/tmp/s48c3 && mkdir -p $W && date > $T
probe_build
ROUNDS=12 timeout 200 $W/probe unc-cloth-ball cloth-90k > $OUT/probe-on.txt 2>&1
echo "probe on rc=$? $(date +%T)" >> $T
PROFILE=0 ROUNDS=12 timeout 100 $W/probe unc-cloth-ball cloth-90k > $OUT/probe-off.txt 2>&1
echo "probe off rc=$? $(date +%T)" >> $T
cp $W/probe-build.log $OUT/
