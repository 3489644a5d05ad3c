#!/bin/bash
# Device call 8 (carry .fcl-debs and .gpu-data; 600 s): the counting order's segment bits
# (KDET_FCL_CUDA_COUNT_ORDER_BITS, an experimental knob; default 16). ncu of the order's five
# launches (KDET_FCL_CUDA_FUSED_ORDER=0) on the two cloth-ball frames at 16 and 18 bits; then
# gpu_bench GPU only on the cloth-ball and n-body scenes, three rounds of 16, 17 and 18 bits.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c8
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target gpu_bench test_cuda_query >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
timeout 60 build-gpu/tests/test_cuda_query --gtest_filter='*Knob*' > $W/knob.log 2>&1
echo "knob test rc=$?" >> $T
B=build-gpu/benchmarks/gpu_bench
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for bits in 16 18; do
  echo "== two frames, bits $bits, five launches" >> $W/ncu.csv
  timeout 100 env KDET_FCL_CUDA_COUNT_ORDER_BITS=$bits KDET_FCL_CUDA_FUSED_ORDER=0 $NCU \
    --clock-control none --kernel-name-base demangled \
    --kernel-name regex:'(orderPairs|scatterPairs|rankPairs|DeviceScan)' \
    --metrics gpu__time_duration.sum,launch__grid_size \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 5 --only unc-cloth-ball-2frames >> $W/ncu.csv 2> $W/ncu-$bits.err
  echo "ncu bits $bits rc=$?" >> $T
  echo "== two frames, bits $bits, fused" >> $W/ncu.csv
  timeout 100 env KDET_FCL_CUDA_COUNT_ORDER_BITS=$bits $NCU \
    --clock-control none --kernel-name-base demangled --kernel-name regex:'orderPairs' \
    --metrics gpu__time_duration.sum,launch__grid_size \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 5 --only unc-cloth-ball-2frames >> $W/ncu.csv 2> $W/ncu-f$bits.err
  echo "ncu fused bits $bits rc=$?" >> $T
done
date >> $T
r=0
for round in 1 2 3; do
  for C in 16 17 18; do
    r=$((r + 1))
    timeout 60 env KDET_FCL_CUDA_COUNT_ORDER_BITS=$C $B --no-fcl --no-cpu --repeats 20 \
      --only unc-cloth-ball --only unc-n-body --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r ($C) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,setting,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$C,/" >> $OUT/bench.csv
  done
done
grep "device memory" $W/bench.log | cut -c1-100 > $OUT/memory.txt
gzip -c $W/ncu.csv > $OUT/ncu.csv.gz
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err 2>/dev/null)
date >> $T
