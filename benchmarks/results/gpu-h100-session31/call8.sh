#!/bin/bash
# Device call 8 (carry .fcl-debs and .gpu-data; 600 s): the second review's tree (the plane
# filter's three launches through one lambda; no behaviour change). Builds the CUDA tests and
# gpu_bench and runs ctest -L cuda; then ncu's durations of the filter on the cloth ball, and
# gpu_bench GPU only on the cloth ball in three processes.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c8
mkdir -p $W
OUT=$W CTEST_ALL=0 JOBS=16 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  timeout 450 scripts/gpu_check.sh > $W/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -30 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
B=build-gpu/benchmarks/gpu_bench
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
timeout 60 $NCU --clock-control none --kernel-name regex:planeFilter \
  --metrics gpu__time_duration.sum,launch__registers_per_thread,launch__grid_size \
  --csv --print-units base $B --no-fcl --no-cpu --repeats 5 --only unc-cloth-ball-self \
  > $OUT/ncu.csv 2> $W/ncu.err
echo "ncu rc=$?" >> $T
for r in 1 2 3; do
  timeout 30 $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball-self --csv $W/p.csv >> $W/bench.log 2>&1
  echo "bench $r rc=$?" >> $T
  if [ $r = 1 ]; then head -1 $W/p.csv | sed 's/^/process,/' > $OUT/bench.csv; fi
  tail -n +2 $W/p.csv | sed "s/^/$r,/" >> $OUT/bench.csv
done
tar czf $OUT/logs.tgz -C $W check.log ctest.log bench.log ncu.err $(cd $W && ls build.log 2>/dev/null)
date >> $T
