#!/bin/bash
# Device call 2 (carry .fcl-debs and .gpu-data; 600 s): kdet_bench with its GPU columns (kDet on
# CUDA and the suite's GPU BVH baseline beside the CPU and FCL OBBRSS, every scene of the suite).
# Builds kdet_bench, runs its smoke configuration (--quick: every pair set checked, GPU included),
# then the suite in two parts (UNC and cloth scenes; the others) while time is left.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c2
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target kdet_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
K=build-gpu/benchmarks/kdet_bench
(lscpu; nproc) > $OUT/cpu.txt 2>&1
timeout 120 $K --quick --no-plots --out $OUT/quick > $W/quick.log 2>&1
echo "quick rc=$?" >> $T
M='kdet_cpu_2t,kdet_gpu,gpu_bvh,fcl_obbrss$'
ARGS="--reps 3 --frames 5 --rep-budget 5 --include-1m --no-kfree --no-plots --methods $M"
left=$((585 - ($(date +%s) - START)))
timeout $left $K $ARGS --only unc,cloth --out $OUT/part1 > $W/part1.log 2>&1
echo "part1 rc=$? ($left s allowed)" >> $T
date >> $T
left=$((585 - ($(date +%s) - START)))
if [ $left -gt 150 ]; then
  timeout $left $K $ARGS --only fracture,nbody,chair,chazelle,huge,coplanar,rigid --out $OUT/part2 > $W/part2.log 2>&1
  echo "part2 rc=$? ($left s allowed)" >> $T
else
  echo "part2 not started ($left s left)" >> $T
fi
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log 2>/dev/null)
date >> $T
