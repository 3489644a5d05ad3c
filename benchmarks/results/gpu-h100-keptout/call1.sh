#!/bin/bash
# Device call 1 (2026-11-24): the read-back probe (a result kept across frames).
set -u
cd benchmarks/results/gpu-h100-keptout
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv > $OUT/nvidia-smi.txt
/usr/local/cuda/bin/nvcc -O2 -std=c++17 -arch=sm_90 readback_probe.cu -o /tmp/rbprobe && /tmp/rbprobe | tee $OUT/probe.txt
nproc >> $OUT/probe.txt; lscpu | grep -i "model name" >> $OUT/probe.txt
