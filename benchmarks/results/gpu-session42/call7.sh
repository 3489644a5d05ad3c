#!/bin/bash
# Device call 7 (carry .fcl-debs/root and .gpu-data): issue 4's targets on this H200 with the
# tree of this session: gpu_bench (kDet's GPU and the LBVH, no FCL, no CPU) on the cloth ball and
# its two frames in six processes, then the 1M and 10M cloths once.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s42c7
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L:$PWD/build-gpu
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target gpu_bench >> $W/build.log 2>&1
echo "build rc=$? $(date +%T)" >> $T
B=build-gpu/benchmarks/gpu_bench
for r in 1 2 3 4 5 6; do
  timeout 60 $B --data $KDET_FCL_DATA_DIR --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball \
    --csv $W/ball-$r.csv >> $W/ball.log 2>&1
  echo "cloth ball $r rc=$? $(date +%T)" >> $T
  if [ $r = 1 ]; then head -1 $W/ball-1.csv | sed 's/^/process,/' > $OUT/ball.csv; fi
  tail -n +2 $W/ball-$r.csv | sed "s/^/$r,/" >> $OUT/ball.csv
done
timeout 240 $B --data $KDET_FCL_DATA_DIR --big --no-fcl --no-cpu --repeats 10 --only cloth-1000k \
  --only cloth-10000k --csv $OUT/big.csv > $W/big.log 2>&1
echo "big rc=$? $(date +%T)" >> $T
grep -i "memory\|B/tri" $W/ball.log $W/big.log | head -20 > $OUT/memory.txt
date >> $T
tar czf $OUT/logs.tgz -C $W ball.log big.log build.log
