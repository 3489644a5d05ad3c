#!/bin/bash
# Device call 12 (carry .fcl-debs/root and .gpu-data; cold machine): kdet_bench after the
# benchmark's two fairness changes (kDet's GPU runs hand updateVertices the positions from a
# buffer the simulation has just filled, untimed, as the GPU BVH's runs do; the hierarchy's
# height, which builds a stale CPU hash, taken in the checking run only) and the final library
# (updateVertices' thread rule). Only the two GPU methods and the reference kdet_cpu_1t, every
# scene, 5 timed runs (FCL's numbers do not depend on these changes: call 8 and 9 have them).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c12
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
nvidia-smi --query-gpu=name --format=csv,noheader > $W/gpu.txt 2>&1
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target kdet_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
M='kdet_gpu$,gpu_bvh$'
for part in 1 2; do
  ONLY=unc,cloth; [ $part = 2 ] && ONLY=fracture,nbody,chair,chazelle,huge,coplanar,rigid
  left=$((330 - ($(date +%s) - START)))
  [ $left -lt 30 ] && { echo "part$part skipped ($left s left)" >> $T; continue; }
  timeout $left build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --include-1m \
    --no-kfree --no-plots --methods $M --only $ONLY --out $W/part$part > $W/part$part.log 2>&1
  echo "part$part rc=$? ($left s allowed)" >> $T
  date >> $T
  tar czf $OUT/out.tgz -C $W .
done
