#!/bin/bash
# Device call 6 (carry .fcl-debs and .gpu-data; 600 s): the final tree on a fresh machine, for
# the spread from machine to machine: the cloth ball in twelve processes and the two cloth-ball
# frames in six, GPU only (kDet GPU and the LBVH in each process).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c6
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
run() {  # $1 scene, $2 processes, $3 output
  for r in $(seq 1 $2); do
    left=$((585 - ($(date +%s) - START)))
    if [ $left -lt 10 ]; then echo "$1 process $r skipped (time)" >> $T; break; fi
    timeout $left $B --no-fcl --no-cpu --repeats 20 --only $1 --csv $W/p.csv >> $W/bench.log 2>&1
    echo "$1 process $r rc=$?" >> $T
    if [ ! -f $OUT/$3 ]; then head -1 $W/p.csv | sed 's/^/process,/' > $OUT/$3; fi
    tail -n +2 $W/p.csv | sed "s/^/$r,/" >> $OUT/$3
  done
}
run unc-cloth-ball-self 12 twelve.csv
run unc-cloth-ball-2frames 6 two-frames.csv
nvidia-smi --query-gpu=name,clocks.max.sm,clocks.sm,driver_version --format=csv > $OUT/gpu.txt 2>&1
tar czf $OUT/logs.tgz -C $W build.log bench.log
date >> $T
