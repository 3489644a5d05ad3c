#!/bin/bash
# Device call 1 (carry .fcl-debs/root and .gpu-data; cold machine): HashedMesh::commitVertices
# (positions written into the mesh's second buffer, checked in place, the buffers traded).
# test_cuda_query (every test, the new CommittedVerticesAreUploadedFromBothRegisteredBuffers
# among them) and test_hierarchy's HashedMesh tests; update_bench on this host; then kdet_bench's
# GPU methods (and the reference kdet_cpu_1t) on the UNC and cloth scenes, commitVertices
# (the default) against updateVertices (--gpu-update copy) in alternating rounds, and the other
# scenes once with the default.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s38c1
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
nvidia-smi --query-gpu=name --format=csv,noheader > $W/gpu.txt 2>&1
lscpu | grep -E 'Model name|^CPU\(s\)' >> $W/gpu.txt
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target kdet_bench test_cuda_query test_hierarchy \
  update_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
B=build-gpu
timeout 200 $B/tests/test_cuda_query > $W/test_cuda_query.log 2>&1
echo "test_cuda_query rc=$? $(grep -E '^\[  (PASSED|FAILED) ' $W/test_cuda_query.log | tr '\n' ' ')" >> $T
timeout 60 $B/tests/test_hierarchy --gtest_filter='HashedMesh.*' > $W/test_hierarchy.log 2>&1
echo "test_hierarchy rc=$? $(grep -E '^\[  (PASSED|FAILED) ' $W/test_hierarchy.log | tr '\n' ' ')" >> $T
for r in 1 2; do timeout 60 $B/benchmarks/update_bench --reps 60 > $W/update_bench$r.md 2>&1; done
echo "update_bench done" >> $T
date >> $T
tar czf $OUT/out.tgz -C $W .
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
run commit1 560 --include-1m --only unc,cloth
run copy1 560 --include-1m --only unc,cloth --gpu-update copy
run other 560 --only fracture,nbody,chair
run commit2 575 --include-1m --only unc,cloth
run copy2 585 --include-1m --only unc,cloth --gpu-update copy
