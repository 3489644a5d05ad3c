#!/bin/bash
# Device call 6 (carry .fcl-debs/root and .gpu-data): with the cells' spans on for meshes of many
# sparse cells, whether the scan of the coarser levels (beside them) should test spans too on
# those meshes: cells_probe.cpp FIRST=1, the defaults against KDET_FCL_CUDA_SPANS=1 (allspans).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s41c6
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L:$PWD/build-gpu
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target kdet_fcl >> $W/build.log 2>&1
echo "lib rc=$?" >> $T
P=benchmarks/results/gpu-session41
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 $P/cells_probe.cpp \
  benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath \
  -Wl,--allow-shlib-undefined -o $W/probe > $W/probe-build.log 2>&1
echo "probe build rc=$?" >> $T
for r in 1 2; do
  FORMS=base,allspans FIRST=1 ROUNDS=7 timeout 120 $W/probe unc-n-body cloth-90k cloth-200k \
    cloth-250k cloth-1000k > $W/probe-$r.txt 2>&1
  echo "probe $r rc=$?" >> $T
done
date >> $T
cp $W/probe-*.txt $OUT/
