#!/bin/bash
# Device call 4 (carry .fcl-debs/root and .gpu-data): the final tree after the new test's mend
# (the default checked after a first query built the hash; KDET_FCL_CUDA_SPANS unset in its
# scope). test_cuda_query, plain and in each of ctest's variant runs (all spans, tile scan,
# rounds, small chunks, order bits), then kdet_bench's GPU form on the UNC and cloth scenes once more.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
left() { echo $((575 - ($(date +%s) - START))); }
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s41c4
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
cmake --build build-gpu --parallel 16 --target kdet_fcl test_cuda_query kdet_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
(cd build-gpu && timeout 200 ctest -R test_cuda_query --output-on-failure > $W/ctest-query.txt 2>&1)
echo "ctest -R test_cuda_query rc=$?" >> $T
tail -n 4 $W/ctest-query.txt >> $T
timeout 60 build-gpu/tests/test_cuda_query > $W/t-new.txt 2>&1
echo "test_cuda_query rc=$?" >> $T
tail -n 3 $W/t-new.txt >> $T
date >> $T
if [ $(left) -gt 60 ]; then
  timeout $(( $(left) - 5 )) build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 \
    --no-kfree --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only unc,cloth \
    --out $W/bench-p1 > $W/bench-p1.log 2>&1
  echo "kdet_bench p1 rc=$?" >> $T
  python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-p1/bench.json > $W/table-p1.md 2>&1
fi
date >> $T
tar czf $OUT/out.tgz -C $W .
cp $W/table-*.md $OUT/ 2>/dev/null
