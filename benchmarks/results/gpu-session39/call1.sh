#!/bin/bash
# Device call 1 (carry .fcl-debs/root and .gpu-data; cold machine): kept worker threads
# (src/cpu/worker_pool.h) instead of threads started per parallel loop.
# 1. The tree with CUDA: test_worker_pool, test_cuda_upload (the staged uploads and the pooled
#    read-backs now on the pool), test_cuda_query, test_hierarchy's HashedMesh tests.
# 2. update_bench (this host's 16 threads) on three CPU-only builds in alternating rounds: the
#    tree before (pool.diff reversed), the tree, and the tree with a finer split of the vertex
#    check (1.5 MB and up, 512 KB a thread, at least 3 threads) to choose the split from.
# 3. kdet_bench's GPU methods on the UNC and cloth scenes (the commit's update column).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s39c1
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader > $W/gpu.txt 2>&1
lscpu | grep -E 'Model name|^CPU\(s\)' >> $W/gpu.txt
CONF=(-DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd
  -Doctomap_DIR=$D/usr/share/octomap -DCMAKE_POLICY_VERSION_MINIMUM=3.5
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L")
cmake -S . -B build-gpu "${CONF[@]}" -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc \
  > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target kdet_bench update_bench test_worker_pool \
  test_cuda_upload test_cuda_query test_hierarchy >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
# The two CPU-only variants, side by side.
SRC=$PWD
for v in base fine; do
  rm -rf /tmp/$v && mkdir -p /tmp/$v && tar cf - --exclude=./build-gpu --exclude=./.gpu-data . | tar xf - -C /tmp/$v
done
(cd /tmp/base && patch -s -R -p1 < benchmarks/results/gpu-session39/pool.diff) >> $W/build.log 2>&1
sed -i 's|^constexpr std::size_t kParallelVertexBytes = std::size_t(4) << 20;|constexpr std::size_t kParallelVertexBytes = std::size_t(1536) << 10;|; s|^constexpr std::size_t kVertexBytesPerThread = std::size_t(2) << 20;|constexpr std::size_t kVertexBytesPerThread = std::size_t(512) << 10;|' /tmp/fine/src/hashed_mesh.cpp
grep -n '^constexpr.*Vertex' /tmp/fine/src/hashed_mesh.cpp >> $W/build.log
for v in base fine; do
  (cmake -S /tmp/$v -B /tmp/$v/b "${CONF[@]}" -DKDET_FCL_CUDA=OFF -DKDET_FCL_BUILD_TESTS=OFF \
     > $W/build-$v.log 2>&1 && cmake --build /tmp/$v/b --parallel 8 --target update_bench \
     >> $W/build-$v.log 2>&1; echo "build $v rc=$?" >> $T) &
done
wait
date >> $T
B=build-gpu
for t in test_worker_pool test_cuda_upload test_cuda_query; do
  timeout 200 $B/tests/$t > $W/$t.log 2>&1
  echo "$t rc=$? $(grep -E '^\[  (PASSED|FAILED) ' $W/$t.log | tr '\n' ' ')" >> $T
done
timeout 60 $B/tests/test_hierarchy --gtest_filter='HashedMesh.*' > $W/test_hierarchy.log 2>&1
echo "test_hierarchy rc=$? $(grep -E '^\[  (PASSED|FAILED) ' $W/test_hierarchy.log | tr '\n' ' ')" >> $T
date >> $T
for r in 1 2 3; do
  for v in base new fine; do
    case $v in new) U=$B/benchmarks/update_bench ;; *) U=/tmp/$v/b/benchmarks/update_bench ;; esac
    for p in float double; do
      a=""; [ $p = double ] && a=--double
      timeout 60 $U --reps 60 $a > $W/update-$v-$p-$r.md 2>&1
    done
  done
done
echo "update_bench done" >> $T
date >> $T
tar czf $OUT/out.tgz -C $W .
left=$((570 - ($(date +%s) - START)))
if [ $left -gt 60 ]; then
  timeout $left $B/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree --no-plots \
    --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only unc,cloth --out $W/part1 > $W/part1.log 2>&1
  echo "part1 rc=$? ($left s allowed)" >> $T
else
  echo "part1 skipped ($left s left)" >> $T
fi
date >> $T
tar czf $OUT/out.tgz -C $W .
