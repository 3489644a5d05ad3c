#!/bin/bash
# Device call 7 (carry .fcl-debs/root and .gpu-data): call 6 found the self query's phase 1
# 6-18 % shorter on the sparse meshes with the scan's spans on too (KDET_FCL_CUDA_SPANS=1). The
# same on every scene that deforms (the small ones too), with the inter queries timed; then
# kdet_bench's GPU form with KDET_FCL_CUDA_SPANS=1 against the defaults, in turn twice.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s41c7
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
(cmake --build build-gpu --parallel 12 --target kdet_bench > $W/build2.log 2>&1; echo "kdet_bench build rc=$?" >> $T) &
BG=$!
P=benchmarks/results/gpu-session41
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 $P/cells_probe.cpp \
  benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath \
  -Wl,--allow-shlib-undefined -o $W/probe > $W/probe-build.log 2>&1
echo "probe build rc=$?" >> $T
FORMS=base,allspans FIRST=1 ROUNDS=7 timeout 150 $W/probe unc-funnel unc-n-body cloth-20k \
  cloth-40k cloth-90k cloth-200k cloth-250k cloth-1000k nbody chair > $W/probe.txt 2>&1
echo "probe rc=$?" >> $T
wait $BG
for tag in base-1 new-1 base-2 new-2; do
  [ ${tag%-*} = new ] && export KDET_FCL_CUDA_SPANS=1
  timeout 110 build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree \
    --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only unc,cloth --out $W/bench-$tag \
    > $W/bench-$tag.log 2>&1
  echo "kdet_bench $tag rc=$?" >> $T
  unset KDET_FCL_CUDA_SPANS
  python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-$tag/bench.json > $W/table-$tag.md 2>&1
done
date >> $T
cp $W/probe.txt $W/table-*.md $OUT/
