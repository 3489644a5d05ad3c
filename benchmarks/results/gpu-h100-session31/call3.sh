#!/bin/bash
# Device call 3 (carry .fcl-debs and .gpu-data; 600 s): the queued plane filter's grid, prefetch
# and register cap (KDET_FCL_CUDA_FILTER_QUEUE 0 to 4), and the exact kernels' grid of one wave
# (KDET_FCL_CUDA_EXACT_RESIDENT). Builds test_cuda_query and gpu_bench; the filter and knob tests,
# then all of test_cuda_query under queue 4 with the exact kernels resident; gpu_bench GPU only in
# three rounds of six settings, one process each; ncu's durations of the filter's and the exact
# kernels' launches on the cloth ball and the two cloth-ball frames in each setting.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
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
cmake --build build-gpu --parallel 16 --target test_cuda_query gpu_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
grep -A2 "planeFilterQueued\|ExactKernel" $W/build.log | grep -i "registers\|spill" | head -20 >> $T
date >> $T
timeout 150 build-gpu/tests/test_cuda_query --gtest_filter='*PlaneFilter*:*Knob*' > $W/tests.log 2>&1
echo "test_cuda_query (filter, knobs) rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED|^\[ filter" $W/tests.log >> $T
KDET_FCL_CUDA_FILTER_QUEUE=4 KDET_FCL_CUDA_EXACT_RESIDENT=1 timeout 240 build-gpu/tests/test_cuda_query > $W/tests-all.log 2>&1
echo "test_cuda_query (all; queue 4, exact resident) rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/tests-all.log >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for round in 1 2 3; do
  for C in 0/0 1/0 2/0 3/0 4/0 3/1; do
    r=$((r + 1))
    Q=${C%/*}; E=${C#*/}
    KDET_FCL_CUDA_FILTER_QUEUE=$Q KDET_FCL_CUDA_EXACT_RESIDENT=$E timeout 60 $B --no-fcl --no-cpu \
      --repeats 20 --only unc-cloth-ball --only unc-funnel-2frames --only unc-n-body-2frames \
      --only cloth-90k --only cloth-1000k --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r (queue $Q, exact resident $E) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,queue,resident,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$Q,$E,/" >> $OUT/bench.csv
  done
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for C in 0/0 1/0 2/0 3/0 4/0 3/1; do
  Q=${C%/*}; E=${C#*/}
  echo "== queue $Q resident $E" >> $W/ncu.csv
  KDET_FCL_CUDA_FILTER_QUEUE=$Q KDET_FCL_CUDA_EXACT_RESIDENT=$E timeout 100 $NCU --clock-control none \
    --kernel-name regex:'planeFilter|ExactKernel' \
    --metrics gpu__time_duration.sum,smsp__inst_executed.sum,launch__registers_per_thread,launch__grid_size,sm__warps_active.avg.pct_of_peak_sustained_active \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 5 --only unc-cloth-ball \
    >> $W/ncu.csv 2> $W/ncu-$Q-$E.err
  echo "ncu queue $Q resident $E rc=$?" >> $T
done
gzip -c $W/ncu.csv > $OUT/ncu.csv.gz
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err)
date >> $T
