#!/bin/bash
# Device call 2 (carry .fcl-debs and .gpu-data; 600 s): the plane filter's last step in closed
# form (no indexed arrays) and in full warps (KDET_FCL_CUDA_FILTER_QUEUE). Builds the new tree and
# the tree before (call2-new.diff reversed) side by side; the new tree's filter and knob tests
# and test_triangle_intersection; gpu_bench GPU only in three rounds of old / new queue 0 / new
# queue 1, one process each; ncu's durations and instruction counts of the filter's launches on
# the cloth ball in each setting.
set -u
cd "$(dirname "$0")/../../.."
R=$PWD
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c2
mkdir -p $W /tmp/old
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
tar cf - --exclude=./build-gpu --exclude=./.git . | (cd /tmp/old && tar xf -)
(cd /tmp/old && patch -R -p1 < $R/benchmarks/results/gpu-h100-session31/call2-new.diff > $W/patch.log 2>&1)
echo "patch rc=$?" >> $T
conf() {
  cmake -S $1 -B $1/build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
    -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
    -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
    "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
    -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc
}
(conf $R > $W/build.log 2>&1 && cmake --build build-gpu --parallel 10 \
  --target test_cuda_query test_triangle_intersection gpu_bench >> $W/build.log 2>&1; echo "build new rc=$?" >> $T) &
(conf /tmp/old > $W/build-old.log 2>&1 && cmake --build /tmp/old/build-gpu --parallel 6 \
  --target gpu_bench >> $W/build-old.log 2>&1; echo "build old rc=$?" >> $T) &
wait
date >> $T
timeout 60 build-gpu/tests/test_triangle_intersection > $W/tri.log 2>&1
echo "test_triangle_intersection rc=$?" >> $T
timeout 150 build-gpu/tests/test_cuda_query --gtest_filter='*PlaneFilter*:*Knob*:*CoplanarPairs*' > $W/tests.log 2>&1
echo "test_cuda_query (filter, knobs) rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED|^\[  SKIPPED|^\[ filter" $W/tests.log >> $T
date >> $T
r=0
for round in 1 2 3; do
  for C in old new0 new1; do
    r=$((r + 1))
    B=build-gpu/benchmarks/gpu_bench
    [ $C = old ] && B=/tmp/old/build-gpu/benchmarks/gpu_bench
    Q=1; [ $C = new0 ] && Q=0
    KDET_FCL_CUDA_FILTER_QUEUE=$Q timeout 60 $B --no-fcl --no-cpu --repeats 20 \
      --only unc-cloth-ball --only unc-funnel-2frames --only unc-n-body-2frames --only cloth-90k \
      --only cloth-1000k --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r ($C) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,tree,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$C,/" >> $OUT/bench.csv
  done
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for C in old new0 new1; do
  B=build-gpu/benchmarks/gpu_bench
  [ $C = old ] && B=/tmp/old/build-gpu/benchmarks/gpu_bench
  Q=1; [ $C = new0 ] && Q=0
  KDET_FCL_CUDA_FILTER_QUEUE=$Q timeout 100 $NCU --clock-control none --kernel-name regex:planeFilter \
    --metrics gpu__time_duration.sum,smsp__inst_executed.sum,launch__registers_per_thread,sm__warps_active.avg.pct_of_peak_sustained_active,smsp__thread_inst_executed_per_inst_executed.ratio \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 5 --only unc-cloth-ball \
    > $W/ncu-$C.csv 2> $W/ncu-$C.err
  echo "ncu $C rc=$?" >> $T
done
cat $W/ncu-old.csv $W/ncu-new0.csv $W/ncu-new1.csv | gzip > $OUT/ncu.csv.gz
date >> $T
KDET_FCL_CUDA_FILTER_QUEUE=1 timeout 100 $NCU --section SourceCounters --section WarpStateStats --section InstructionStats \
  --kernel-name regex:planeFilter --launch-skip 4 --launch-count 1 --print-details all \
  build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 10 --only unc-cloth-ball-self > $W/ncu-detail-new1.txt 2>&1
echo "ncu detail rc=$?" >> $T
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err ncu-detail-new1.txt)
date >> $T
