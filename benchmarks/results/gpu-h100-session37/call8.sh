#!/bin/bash
# Device call 8 (carry .fcl-debs and .gpu-data; 600 s): the cut-off try's tree finished (topology
# version, updateVertices in threads, kdet_bench's GPU columns with the GPU methods' objects kept
# from run to run). Builds the library, test_cuda_query, test_hierarchy, kdet_bench and gpu_bench;
# runs test_cuda_query (all) and test_hierarchy's HashedMesh tests; then kdet_bench on the UNC and
# cloth scenes (part 1) with kDet on CUDA, the GPU BVH, kDet CPU 2T and FCL OBBRSS in one process.
# build-gpu stays for call 9 on the warm machine.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=$OUT/c8
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
nvidia-smi --query-gpu=name,compute_cap,memory.total,driver_version --format=csv > $W/gpu.txt 2>&1
(lscpu; nproc) > $W/cpu.txt 2>&1
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target kdet_fcl test_cuda_query test_hierarchy kdet_bench gpu_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
timeout 200 build-gpu/tests/test_cuda_query > $W/query.log 2>&1
echo "test_cuda_query rc=$?: $(grep -E '^\[  (PASSED|FAILED)' $W/query.log | tr '\n' ' ')" >> $T
timeout 60 build-gpu/tests/test_hierarchy --gtest_filter='HashedMesh.*' > $W/hier.log 2>&1
echo "test_hierarchy HashedMesh rc=$?: $(grep -E '^\[  (PASSED|FAILED)' $W/hier.log | tr '\n' ' ')" >> $T
date >> $T
M='kdet_cpu_2t,kdet_gpu,gpu_bvh,fcl_obbrss$'
left=$((575 - ($(date +%s) - START)))
timeout $left build-gpu/benchmarks/kdet_bench --reps 3 --frames 5 --rep-budget 5 --include-1m \
  --no-kfree --no-plots --methods $M --only unc,cloth --out $W/part1 > $W/part1.log 2>&1
echo "part1 rc=$? ($left s allowed)" >> $T
date >> $T
