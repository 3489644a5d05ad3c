#!/bin/bash
# Device call 3 (carry .fcl-debs and .gpu-data; 600 s): the committed change (short sums of the
# exact orientations, exact zeros in the filter's last step, the exact kernels' resident grid).
# Builds; the full run with every peer in one process (gpu_bench --big --repeats 10); the cloth
# ball in twelve processes; the new device test and compute-sanitizer memcheck and racecheck of
# it and of test_cuda_query's tests of the exact kernels (coplanar pairs; the filter on, off and
# overflowing).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c3
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_query test_cuda_predicates gpu_bench >> $W/build.log 2>&1
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
timeout 60 build-gpu/tests/test_cuda_predicates > $W/predicates.log 2>&1
echo "test_cuda_predicates rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) " $W/predicates.log >> $T
for tool in memcheck racecheck; do
  timeout $(( (590 - ($(date +%s) - START)) / 4 )) $CS --tool $tool --error-exitcode 3 build-gpu/tests/test_cuda_predicates \
    > $W/$tool-predicates.log 2>&1
  echo "$tool predicates test rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED) |ERROR SUMMARY|RACECHECK SUMMARY" $W/$tool-predicates.log >> $T
  timeout $(( (590 - ($(date +%s) - START)) / 3 )) $CS --tool $tool --error-exitcode 3 \
    build-gpu/tests/test_cuda_query --gtest_filter='*CoplanarPairsOfTheExactKernel*:*PlaneFilterOnOff*' > $W/$tool-exact.log 2>&1
  echo "$tool exact-kernel tests rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED) |ERROR SUMMARY|RACECHECK SUMMARY" $W/$tool-exact.log >> $T
done
date >> $T
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log)
date >> $T
