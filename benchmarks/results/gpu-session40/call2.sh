#!/bin/bash
# Device call 2: snoop_probe.cu with the demote (CLDEMOTE) and non-temporal-prefetch scenarios,
# at 13.5, 3.0 and 1.1 MB (the 1M, 250k and 92k cloths' positions in double), twice at 13.5.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
W=/tmp/s40c2
mkdir -p $W
P=benchmarks/results/gpu-session40
/usr/local/cuda/bin/nvcc -O3 -std=c++17 -arch=sm_90 -Xcompiler -O3,-march=native $P/snoop_probe.cu -o $W/snoop > $W/snoop-build.log 2>&1
echo "snoop build rc=$?" >> $T
for mb in 13.5 3.0 1.1 13.5; do
  timeout 90 $W/snoop $mb 40 >> $OUT/snoop.txt 2>&1
  echo "snoop $mb rc=$?" >> $T
done
date >> $T
