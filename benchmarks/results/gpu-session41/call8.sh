#!/bin/bash
# Device call 8 (carry .fcl-debs/root and .gpu-data): where kdet_bench's time goes with the
# scan's spans on (KDET_FCL_CUDA_SPANS=1), which call 7's probe found faster and kdet_bench
# slower. The UNC n-body only: kdet_bench with kDet's GPU method alone (no LBVH frames between
# kDet's) in turn with the defaults, twice; then with the LBVH too, once each; then ncu of the
# candidate kernels in a short kdet_bench run per setting.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s41c8
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L:$PWD/build-gpu
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target kdet_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
B=build-gpu/benchmarks/kdet_bench
run() {  # tag, spans 0|1, methods
  [ $2 = 1 ] && export KDET_FCL_CUDA_SPANS=1
  timeout 60 $B --reps 5 --frames 5 --rep-budget 5 --no-kfree --no-plots --methods "$3" \
    --only unc-n-body --out $W/bench-$1 > $W/bench-$1.log 2>&1
  echo "kdet_bench $1 rc=$?" >> $T
  unset KDET_FCL_CUDA_SPANS
  python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-$1/bench.json > $W/table-$1.md 2>&1
  { echo "== $1"; grep '^| unc' $W/table-$1.md; } >> $OUT/tables.txt
}
for r in 1 2; do
  run kdet-base-$r 0 'kdet_gpu$'
  run kdet-spans-$r 1 'kdet_gpu$'
done
run both-base 0 'kdet_gpu$,gpu_bvh$'
run both-spans 1 'kdet_gpu$,gpu_bvh$'
for k in 0 1; do
  [ $k = 1 ] && export KDET_FCL_CUDA_SPANS=1
  timeout 90 ncu --clock-control none --kernel-name-base demangled \
    --kernel-name regex:'Candidates|CellPairs|Filter|Exact|rder' \
    --metrics gpu__time_duration.sum --csv --print-units base \
    $B --reps 2 --frames 3 --rep-budget 2 --no-kfree --no-plots --methods 'kdet_gpu$' \
    --only unc-n-body --out $W/ncu-bench-$k > $W/ncu-$k.csv 2> $W/ncu-$k.err
  echo "ncu $k rc=$?" >> $T
  cp $W/ncu-$k.csv $OUT/
  unset KDET_FCL_CUDA_SPANS
done
date >> $T
tar czf $OUT/out.tgz -C $W --exclude='bench-*' .
