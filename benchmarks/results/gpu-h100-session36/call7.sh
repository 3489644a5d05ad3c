#!/bin/bash
# Device call 7 (carry .fcl-debs and .gpu-data; 600 s): the final tree. ncu's duration of every
# kernel of the two cloth-ball frames (one round of 5-byte candidates) and of the cloth ball,
# gpu_bench GPU only, 5 repeats (ncu_kernels.py sums them per kernel).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c7
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target gpu_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in unc-cloth-ball-2frames unc-cloth-ball-self; do
  left=$((585 - ($(date +%s) - START)))
  if [ $left -lt 30 ]; then echo "ncu $sc skipped (time)" >> $T; continue; fi
  echo "== $sc" >> $W/ncu.csv
  timeout $((left - 10)) $NCU --clock-control none --kernel-name-base demangled \
    --metrics gpu__time_duration.sum,launch__grid_size \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 5 --only $sc >> $W/ncu.csv 2> $W/ncu-$sc.err
  echo "ncu $sc rc=$?" >> $T
done
gzip -c $W/ncu.csv > $OUT/ncu.csv.gz
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err 2>/dev/null)
date >> $T
