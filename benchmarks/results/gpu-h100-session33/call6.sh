#!/bin/bash
# Device call 6 (carry .fcl-debs and .gpu-data; 600 s): the committed tree b12572c. Runs
# scripts/gpu_check.sh (ctest -L cuda) and ncu's durations of the phase-1 kernels on the cloth
# ball, the 90k cloth and the 1M cloth (the kernels without spans as before the queue).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
W=$OUT/gc
OUT=$W CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh test_cuda_warp_search gpu_bench" \
  timeout 450 scripts/gpu_check.sh > $OUT/gpu_check.log 2>&1
echo "gpu_check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -20 >> $T
gzip $W/ctest.log $W/build.log
date >> $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
echo "== new" > $OUT/ncu.csv
timeout 100 $NCU --clock-control none --kernel-name-base demangled \
  --kernel-name regex:'kdet_fcl::cuda.*(CandidatesWarp|CellPairs)' \
  --metrics gpu__time_duration.sum,smsp__inst_executed.sum,launch__registers_per_thread \
  --csv --print-units base build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 3 \
  --only unc-cloth-ball-self --only cloth-90k --only cloth-1000k >> $OUT/ncu.csv 2> $OUT/ncu.err
echo "ncu rc=$?" >> $T
gzip $OUT/ncu.csv
date >> $T
