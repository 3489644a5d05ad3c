#!/bin/bash
# Device call 5 (carry .fcl-debs and .gpu-data; 600 s): the final tree (the queue of seen entries
# in the kernels with spans; the cells' kernel without spans passes its row's entry directly).
# Builds gpu_bench, test_cuda_query and test_cuda_warp_search; compute-sanitizer memcheck and
# racecheck of the ring's test and of the span-choice test with spans always on; the full
# gpu_bench run with every peer in one process (--big --repeats 10); then the cloth ball in
# twelve processes, GPU only.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c5
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_query test_cuda_warp_search gpu_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
left=$((420 - ($(date +%s) - START)))
timeout $left $B --big --repeats 10 --csv $OUT/gpu_bench.csv --json $OUT/gpu_bench.json \
  --md $OUT/gpu_bench.md > $W/gpu_bench.log 2>&1
echo "full run rc=$?" >> $T
date >> $T
for r in $(seq 1 12); do
  left=$((450 - ($(date +%s) - START)))
  if [ $left -lt 10 ]; then echo "process $r skipped (time)" >> $T; break; fi
  timeout $left $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball-self --csv $W/p-$r.csv >> $W/twelve.log 2>&1
  echo "process $r rc=$?" >> $T
  if [ $r = 1 ]; then head -1 $W/p-1.csv | sed 's/^/process,/' > $OUT/twelve.csv; fi
  tail -n +2 $W/p-$r.csv | sed "s/^/$r,/" >> $OUT/twelve.csv
done
CS=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
for tool in memcheck racecheck; do
  timeout $(( (590 - ($(date +%s) - START)) / 4 )) $CS --tool $tool --error-exitcode 3 build-gpu/tests/test_cuda_warp_search \
    --gtest_filter='*Ring*' > $W/$tool-ring.log 2>&1
  echo "$tool ring test rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED) |ERROR SUMMARY|RACECHECK SUMMARY" $W/$tool-ring.log >> $T
  KDET_FCL_CUDA_SPANS=1 timeout $(( (590 - ($(date +%s) - START)) / 3 )) $CS --tool $tool --error-exitcode 3 \
    build-gpu/tests/test_cuda_query --gtest_filter='*SubcellSpanChoice*' > $W/$tool-spans.log 2>&1
  echo "$tool span-choice test rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED) |ERROR SUMMARY|RACECHECK SUMMARY" $W/$tool-spans.log >> $T
done
date >> $T
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log)
date >> $T
