#!/bin/bash
# Device call 1 (carry .fcl-debs and .gpu-data; 600 s): the tree of df3d95e. The packed
# read-back probe (packed_readback_probe.cu) while gpu_bench builds; then ncu of the counting
# order's five launches (KDET_FCL_CUDA_FUSED_ORDER=0) at the default 17 bits on the two
# cloth-ball frames and the two n-body frames (the rank's share), and of every kernel of the
# 20k and 90k cloths (where the sparse frames go).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c1
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
(cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1 &&
  cmake --build build-gpu --parallel 14 --target gpu_bench >> $W/build.log 2>&1; echo $? > $W/build.rc) &
P=benchmarks/results/gpu-h100-session37/packed_readback_probe.cu
/usr/local/cuda/bin/nvcc -O3 -arch=sm_90 -Xcompiler -fopenmp $P -o /tmp/probe > $W/probe-build.log 2>&1
echo "probe build rc=$?" >> $T
taskset -c 12-15 timeout 60 /tmp/probe > $OUT/probe.txt 2>&1
echo "probe rc=$?" >> $T
wait
echo "build rc=$(cat $W/build.rc)" >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in unc-cloth-ball-2frames unc-n-body-2frames; do
  echo "== $sc, five launches" >> $W/ncu.csv
  timeout 90 env KDET_FCL_CUDA_FUSED_ORDER=0 $NCU \
    --clock-control none --kernel-name-base demangled \
    --kernel-name regex:'(orderPairs|scatterPairs|rankPairs|DeviceScan)' \
    --metrics gpu__time_duration.sum,launch__grid_size \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 5 --only $sc >> $W/ncu.csv 2> $W/ncu-$sc.err
  echo "ncu $sc rc=$?" >> $T
done
for sc in cloth-20k cloth-90k; do
  left=$((585 - ($(date +%s) - START)))
  if [ $left -lt 30 ]; then echo "ncu $sc skipped (time)" >> $T; continue; fi
  echo "== $sc" >> $W/ncu.csv
  timeout $((left - 10)) $NCU --clock-control none --kernel-name-base demangled \
    --metrics gpu__time_duration.sum,launch__grid_size \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 3 --only $sc >> $W/ncu.csv 2> $W/ncu-$sc.err
  echo "ncu $sc rc=$?" >> $T
done
gzip -c $W/ncu.csv > $OUT/ncu.csv.gz
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err 2>/dev/null)
date >> $T
