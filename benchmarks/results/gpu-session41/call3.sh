#!/bin/bash
# Device call 3 (carry .fcl-debs/root and .gpu-data): the final rule (the cells' own span filter
# where the scan tests spans or the mesh has many sparse cells). cells_probe.cpp with FIRST=1:
# the new default (base) against KDET_FCL_CUDA_CELL_SPANS=0 (the old choice on the sparse
# meshes), then the 250k and 1M cloths with 8 and 16 rows per task; every CUDA test (ctest -L
# cuda); kdet_bench's GPU form on every scene group once.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
left() { echo $((575 - ($(date +%s) - START))); }
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s41c3
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
(cmake --build build-gpu --parallel 12 --target kdet_bench test_cuda_device test_cuda_query \
  test_cuda_bvh test_cuda_upload test_cuda_box_test test_cuda_warp_search test_cuda_predicates \
  > $W/build2.log 2>&1; echo "bench+tests build rc=$?" >> $T) &
BG=$!
P=benchmarks/results/gpu-session41
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 $P/cells_probe.cpp \
  benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath \
  -Wl,--allow-shlib-undefined -o $W/probe > $W/probe-build.log 2>&1
echo "probe build rc=$?" >> $T
FORMS=base,nospans FIRST=1 ROUNDS=7 timeout 150 $W/probe unc-n-body cloth-90k cloth-200k \
  cloth-250k cloth-1000k > $W/probe.txt 2>&1
echo "probe rc=$?" >> $T
FORMS=base,spans-r16,spans-r8 FIRST=1 ROUNDS=7 timeout 100 $W/probe cloth-250k cloth-1000k \
  > $W/probe-rows.txt 2>&1
echo "probe rows rc=$?" >> $T
date >> $T
wait $BG
(cd build-gpu && timeout 240 ctest -L cuda --output-on-failure > $W/ctest-cuda.txt 2>&1)
echo "ctest -L cuda rc=$?" >> $T
tail -n 4 $W/ctest-cuda.txt >> $T
date >> $T
bench() {  # tag, --only
  timeout $(( $(left) - 5 )) build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 \
    --no-kfree --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only $2 \
    --out $W/bench-$1 > $W/bench-$1.log 2>&1
  echo "kdet_bench $1 rc=$?" >> $T
  python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-$1/bench.json > $W/table-$1.md 2>&1
}
if [ $(left) -gt 60 ]; then bench p1 unc,cloth; fi
if [ $(left) -gt 50 ]; then bench p2 fracture,nbody,chair; fi
date >> $T
tar czf $OUT/out.tgz -C $W --exclude=probe .
cp $W/probe*.txt $W/table-*.md $OUT/ 2>/dev/null
