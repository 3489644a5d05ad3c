#!/bin/bash
# Device call 3 (carry .fcl-debs and .gpu-data; 600 s): the final tree of the packed candidates.
# scripts/gpu_check.sh (every CUDA test program and gpu_bench built, ctest -L cuda); the two
# cloth-ball scenes (self, and the two frames hashed as one) in twelve processes, GPU only; then
# readback_probe.cu (where the two frames' 3.6 MB read-back goes).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=$OUT/gc
OUT=$W CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh test_cuda_warp_search test_cuda_predicates gpu_bench" \
  timeout 400 scripts/gpu_check.sh > $OUT/gpu_check.log 2>&1
echo "gpu_check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -20 >> $T
gzip $W/ctest.log $W/build.log
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
B=build-gpu/benchmarks/gpu_bench
for r in $(seq 1 12); do
  left=$((540 - ($(date +%s) - START)))
  if [ $left -lt 10 ]; then echo "process $r skipped (time)" >> $T; break; fi
  timeout $left $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --csv /tmp/p-$r.csv >> /tmp/twelve.log 2>&1
  echo "process $r rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/p-1.csv | sed 's/^/process,/' > $OUT/twelve.csv; fi
  tail -n +2 /tmp/p-$r.csv | sed "s/^/$r,/" >> $OUT/twelve.csv
done
date >> $T
P=benchmarks/results/gpu-h100-session36/readback_probe.cu
/usr/local/cuda/bin/nvcc -O3 -arch=sm_90 -Xcompiler -fopenmp $P -o /tmp/probe > /tmp/probe-build.log 2>&1
echo "probe build rc=$?" >> $T
timeout 40 /tmp/probe > $OUT/probe.txt 2>&1
echo "probe rc=$?" >> $T
gzip -c /tmp/twelve.log > $OUT/twelve.log.gz
date >> $T
