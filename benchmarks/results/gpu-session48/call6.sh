#!/bin/bash
# Device call 6 of session 48, on call 5's machine (its build-gpu and /tmp/s48c5/probe; carry
# .fcl-debs/root and .gpu-data). The machine had no Nsight Systems (call 5), so ncu's kernel
# durations (no clock control, kernels serialised) of precision_probe.cpp's frames instead:
# double only, profiling off, rounds 0-2, each scene in a process of its own. (Run as one
# command line; written here as a script.)
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
W=/tmp/s48c5
date > $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in cloth-90k unc-cloth-ball; do
  ONLY=double PROFILE=0 ROUNDS=2 timeout 200 $NCU --clock-control none \
    --metrics gpu__time_duration.sum --csv --print-units base $W/probe $sc \
    > $W/ncu-$sc.csv 2> $W/ncu-$sc.err
  echo "ncu $sc rc=$? $(date +%T)" >> $T
done
gzip -c $W/ncu-cloth-90k.csv > $OUT/ncu-cloth-90k.csv.gz
gzip -c $W/ncu-unc-cloth-ball.csv > $OUT/ncu-unc-cloth-ball.csv.gz
