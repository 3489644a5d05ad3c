#!/bin/bash
# Device call 2 (carry .fcl-debs/root and .gpu-data): the cells' own span filter
# (KDET_FCL_CUDA_CELL_SPANS) without the index-first form. cells_probe.cpp with FIRST=1 (each
# frame's first self query, which re-hashes, in one form: base or spans, rotated) on the sparse
# scenes; test_cuda_query; kdet_bench on the UNC and cloth scenes with the defaults and with
# KDET_FCL_CUDA_CELL_SPANS=1, in turn, twice.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
left() { echo $((575 - ($(date +%s) - START))); }
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s41c2
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L:$PWD/build-gpu
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader > $W/gpu.txt 2>&1
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target kdet_fcl >> $W/build.log 2>&1
echo "lib rc=$?" >> $T
(cmake --build build-gpu --parallel 12 --target kdet_bench test_cuda_query > $W/build2.log 2>&1; echo "bench+test build rc=$?" >> $T) &
BG=$!
P=benchmarks/results/gpu-session41
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 $P/cells_probe.cpp \
  benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath \
  -Wl,--allow-shlib-undefined -o $W/probe > $W/probe-build.log 2>&1
echo "probe build rc=$?" >> $T
date >> $T
FIRST=1 ROUNDS=7 timeout 200 $W/probe unc-n-body unc-funnel cloth-20k cloth-40k cloth-90k \
  cloth-200k cloth-250k cloth-1000k > $W/probe.txt 2>&1
echo "probe rc=$?" >> $T
date >> $T
wait $BG
timeout 100 build-gpu/tests/test_cuda_query > $W/t-query.txt 2>&1; echo "test_cuda_query rc=$?" >> $T
tail -n 3 $W/t-query.txt >> $T
bench() {  # tag, cell knobs 0|1
  if [ $2 = 1 ]; then export KDET_FCL_CUDA_CELL_SPANS=1; fi
  timeout $(( $(left) - 5 )) build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 \
    --no-kfree --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only unc,cloth \
    --out $W/bench-$1 > $W/bench-$1.log 2>&1
  echo "kdet_bench $1 rc=$?" >> $T
  python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-$1/bench.json > $W/table-$1.md 2>&1
  unset KDET_FCL_CUDA_CELL_SPANS
}
for tag in base-1 new-1 base-2 new-2; do
  if [ $(left) -lt 60 ]; then echo "bench $tag skipped (time)" >> $T; continue; fi
  bench $tag $([ ${tag%-*} = new ] && echo 1 || echo 0)
done
date >> $T
tar czf $OUT/out.tgz -C $W --exclude=probe .
cp $W/probe.txt $W/table-*.md $OUT/ 2>/dev/null
