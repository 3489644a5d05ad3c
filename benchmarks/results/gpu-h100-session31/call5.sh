#!/bin/bash
# Device call 5 (carry .fcl-debs and .gpu-data; 600 s): the final tree. Builds gpu_bench and
# test_cuda_query, and beside them a mutant copy of the tree (the queued plane filter without its
# final drain: the pairs left in a warp's queue are lost; call 4's copy did not link) whose filter
# test must fail while the tree's passes; then the full gpu_bench run with every peer in one
# process (--big --repeats 10); then the cloth ball in twelve processes, GPU only.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c5
mkdir -p $W /tmp/mut
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
tar cf - --exclude=./build-gpu --exclude=./.git . | (cd /tmp/mut && tar xf -)
sed -i 's/^  if (lane < fill) finish(qk\[lane\], qs\[lane\]);$/  \/\/ (mutant: no drain)/' /tmp/mut/cuda/cuda_backend.cu
grep -c "(mutant: no drain)" /tmp/mut/cuda/cuda_backend.cu >> $T
conf() {
  cmake -S $1 -B $1/build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
    -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
    -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
    "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
    -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc
}
(conf $PWD > $W/build.log 2>&1 && cmake --build build-gpu --parallel 10 \
  --target test_cuda_query gpu_bench >> $W/build.log 2>&1; echo "build rc=$?" >> $T) &
(conf /tmp/mut > $W/build-mut.log 2>&1 && cmake --build /tmp/mut/build-gpu --parallel 6 \
  --target test_cuda_query >> $W/build-mut.log 2>&1; echo "mutant build rc=$?" >> $T) &
wait
date >> $T
F='CudaQuery.PlaneFilterOnOff*'
timeout 60 /tmp/mut/build-gpu/tests/test_cuda_query --gtest_filter="$F" > $W/tests-mut.log 2>&1
echo "mutant filter test rc=$? (must be non-zero)" >> $T
grep -E "^\[  (PASSED|FAILED) " $W/tests-mut.log >> $T; grep -c "Failure" $W/tests-mut.log >> $T
grep -o "filter 1 decides 1 queue [01] cap '[0-9]*'" $W/tests-mut.log | sort | uniq -c >> $T
timeout 60 build-gpu/tests/test_cuda_query --gtest_filter="$F" > $W/tests.log 2>&1
echo "filter test rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) " $W/tests.log >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
left=$((560 - ($(date +%s) - START)))
timeout $left $B --big --repeats 10 --csv $OUT/gpu_bench.csv --json $OUT/gpu_bench.json \
  --md $OUT/gpu_bench.md > $W/gpu_bench.log 2>&1
echo "full run rc=$?" >> $T
date >> $T
for r in $(seq 1 12); do
  left=$((585 - ($(date +%s) - START)))
  if [ $left -lt 10 ]; then echo "process $r skipped (time)" >> $T; break; fi
  timeout $left $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball-self --csv $W/p-$r.csv >> $W/twelve.log 2>&1
  echo "process $r rc=$?" >> $T
  if [ $r = 1 ]; then head -1 $W/p-1.csv | sed 's/^/process,/' > $OUT/twelve.csv; fi
  tail -n +2 $W/p-$r.csv | sed "s/^/$r,/" >> $OUT/twelve.csv
done
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log)
date >> $T
