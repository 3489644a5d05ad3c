#!/bin/bash
# Device call 2 (carry .fcl-debs/root and .gpu-data): kdet_bench's GPU methods now read each
# query's pairs back into a result kept from frame to frame (kDet: intersectMeshes/intersectSelf
# into a result; the GPU BVH: its `keep`), as gpu_bench's do. kdet_gpu and gpu_bvh (and the
# reference kdet_cpu_1t) on the UNC and cloth scenes: kept results (the default) against
# --fresh-results in alternating rounds, both with commitVertices; then the other scenes once.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s38c2
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
B=build-gpu
M='kdet_gpu$,gpu_bvh$'
run() {  # name, budget end (s since START), args...
  local name=$1 end=$2; shift 2
  local left=$((end - ($(date +%s) - START)))
  [ $left -lt 40 ] && { echo "$name skipped ($left s left)" >> $T; return; }
  timeout $left $B/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree \
    --no-plots --methods $M --out $W/$name "$@" > $W/$name.log 2>&1
  echo "$name rc=$? ($left s allowed)" >> $T
  date >> $T
  tar czf $OUT/out.tgz -C $W .
}
run kept1 560 --include-1m --only unc,cloth
run fresh1 560 --include-1m --only unc,cloth --fresh-results
run other 560 --only fracture,nbody,chair,chazelle,huge,coplanar,rigid
run kept2 575 --include-1m --only unc,cloth
run fresh2 585 --include-1m --only unc,cloth --fresh-results
