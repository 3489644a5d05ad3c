#!/bin/bash
# Device call 1 (carry .fcl-debs and .gpu-data; 600 s): the deciding plane filter in phase 1's
# kernels (KDET_FCL_CUDA_FUSED_FILTER), inlined (build-gpu) or called out of line
# (build-ni: -DKDET_FUSED_NOINLINE). Builds test_cuda_query and gpu_bench in both; the filter and
# knob tests, then all of test_cuda_query (the fused filter is the default); gpu_bench GPU only
# in two rounds of three settings (fused 0, fused inlined, fused out of line), one process each;
# ncu's durations of phase 1, the filter and the exact kernels on the cloth ball and the two
# cloth-ball frames in each setting.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c1
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
conf() {
  cmake -S . -B $1 -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
    -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
    -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
    "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
    -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc "$2" > $W/$1.log 2>&1
  cmake --build $1 --parallel 8 --target test_cuda_query gpu_bench >> $W/$1.log 2>&1
  echo "build $1 rc=$?" >> $T
}
conf build-gpu -DKDET_FCL_DUMMY=0 &
conf build-ni "-DCMAKE_CUDA_FLAGS=-DKDET_FUSED_NOINLINE" &
wait
date >> $T
timeout 150 build-gpu/tests/test_cuda_query --gtest_filter='*PlaneFilter*:*Knob*' > $W/tests.log 2>&1
echo "test_cuda_query (filter, knobs) rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED|^\[ filter" $W/tests.log >> $T
timeout 240 build-gpu/tests/test_cuda_query > $W/tests-all.log 2>&1
echo "test_cuda_query (all) rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/tests-all.log >> $T
timeout 150 build-ni/tests/test_cuda_query --gtest_filter='*PlaneFilter*' > $W/tests-ni.log 2>&1
echo "test_cuda_query (filter; out of line) rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/tests-ni.log >> $T
date >> $T
r=0
for round in 1 2; do
  for C in gpu/0 gpu/1 ni/1; do
    r=$((r + 1))
    Bd=${C%/*}; F=${C#*/}
    KDET_FCL_CUDA_FUSED_FILTER=$F timeout 80 build-$Bd/benchmarks/gpu_bench --no-fcl --no-cpu \
      --repeats 20 --only unc-cloth-ball --only unc-funnel-2frames --only unc-n-body-2frames \
      --only cloth-90k --only cloth-1000k --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r ($Bd, fused $F) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,build,fused,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$Bd,$F,/" >> $OUT/bench.csv
  done
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for C in gpu/0 gpu/1 ni/1; do
  Bd=${C%/*}; F=${C#*/}
  echo "== $Bd fused $F" >> $W/ncu.csv
  KDET_FCL_CUDA_FUSED_FILTER=$F timeout 100 $NCU --clock-control none \
    --kernel-name regex:'Candidates|CellPairs|planeFilter|ExactKernel' \
    --metrics gpu__time_duration.sum,smsp__inst_executed.sum,launch__registers_per_thread,launch__grid_size,sm__warps_active.avg.pct_of_peak_sustained_active \
    --csv --print-units base build-$Bd/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 3 \
    --only unc-cloth-ball >> $W/ncu.csv 2> $W/ncu-$Bd-$F.err
  echo "ncu $Bd fused $F rc=$?" >> $T
done
gzip -c $W/ncu.csv > $OUT/ncu.csv.gz
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err)
date >> $T
