#!/bin/bash
# Device call 5 of session 48 (carry .fcl-debs/root and .gpu-data; a fresh machine): where the
# GPU frame of kdet_bench's form goes beyond the query's phases. precision_probe.cpp (ONLY=one
# precision, PROFILE=0, 10 rounds) under Nsight Systems (CUDA trace only) on the 90k cloth and
# the UNC cloth ball, in double and in float: its kernels, copies and API calls summed, and the
# GPU trace (each kernel's and copy's start and length) as CSV, from which trace_gaps.py takes
# the device's busy time and its idle gaps per frame.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
. benchmarks/results/gpu-session48/probe_build.sh  # (the run had its command inline)
ab_configure /tmp/s48c5
cmake --build build-gpu --parallel 16 --target kdet_fcl >> $W/build.log 2>&1
echo "lib rc=$? $(date +%T)" >> $T
probe_build
NSYS=$(command -v nsys || ls /usr/local/cuda/bin/nsys /opt/nvidia/nsight-systems/*/bin/nsys \
  /usr/local/cuda/nsight-systems*/bin/nsys 2>/dev/null | head -1)
echo "nsys: ${NSYS:-none} $($NSYS --version 2>&1 | head -1)" >> $T
for scene in cloth-90k unc-cloth-ball; do
  for p in double float; do
    n=$scene-$p
    ONLY=$p PROFILE=0 ROUNDS=10 timeout 90 $NSYS profile -t cuda --sample=none --cpuctxsw=none \
      -o $W/trace-$n $W/probe $scene > $W/probe-$n.txt 2>&1
    echo "nsys $n rc=$? $(date +%T)" >> $T
    timeout 90 $NSYS stats -q -r cuda_gpu_kern_sum,cuda_gpu_mem_time_sum,cuda_api_sum,cuda_gpu_trace \
      -f csv -o $W/stats-$n $W/trace-$n.nsys-rep > $W/stats-$n.log 2>&1
    echo "stats $n rc=$? $(date +%T)" >> $T
    ls $W/stats-$n* >> $T
  done
done
cat $W/probe-*.txt | grep -v "^kdet_bench:" > $OUT/probes.txt
tar czf $OUT/stats.tgz -C $W --exclude='*.nsys-rep' --exclude='*.sqlite' --exclude=probe .
date >> $T
