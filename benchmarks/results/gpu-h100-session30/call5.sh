#!/bin/bash
# Device call 5 (carry .fcl-debs and .gpu-data; 600 s): the final tree's cloth ball in twelve
# processes (gpu_bench without FCL and the CPU: kDet GPU and the LBVH in each process), for the
# spread of the ratio; then the one trip's order launch at 2 (default), 4 and 8 blocks per SM
# (KDET_FCL_CUDA_FUSED_ORDER), now that it writes results of up to 4 chunks into the stage:
# three rounds in turn, one process each.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c5
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
for p in 1 2 3 4 5 6 7 8 9 10 11 12; do
  timeout 60 $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball-self --csv $W/ball-$p.csv \
    >> $W/ball.log 2>&1
  echo "cloth ball process $p rc=$?" >> $T
  if [ $p = 1 ]; then head -1 $W/ball-1.csv | sed 's/^/process,/' > $OUT/ball.csv; fi
  tail -n +2 $W/ball-$p.csv | sed "s/^/$p,/" >> $OUT/ball.csv
done
date >> $T
r=0
for round in 1 2 3; do
  for K in 2 4 8; do
    r=$((r + 1))
    KDET_FCL_CUDA_FUSED_ORDER=$K timeout 60 $B --no-fcl --no-cpu --repeats 20 \
      --only unc-cloth-ball --only unc-funnel --only unc-n-body --csv $W/bench-$r.csv \
      >> $W/bench.log 2>&1
    echo "bench $r (fused order $K) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,blocks,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$K,/" >> $OUT/bench.csv
  done
done
date >> $T
tar czf $OUT/logs.tgz -C $W build.log ball.log bench.log
date >> $T
