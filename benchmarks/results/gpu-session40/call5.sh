#!/bin/bash
# Device call 5 (carry .fcl-debs/root and .gpu-data): the final rule (a pass leaves the caches
# only where it runs in several threads: commitVertices' demotion was on for every registered
# buffer in call 4, and cost the one-thread commits of the small scenes more than it saved).
# kdet_bench's GPU form, KDET_FCL_DMA_PASSES=0 against unset in turn: the UNC and cloth scenes
# twice, then test_cuda_upload and test_cuda_query, then the other scenes once each.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
left() { echo $((575 - ($(date +%s) - START))); }
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s40c5
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
cmake --build build-gpu --parallel 16 --target kdet_fcl kdet_bench test_cuda_query test_cuda_upload >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
bench() {  # knob, tag, --only
  if [ $1 = 0 ]; then export KDET_FCL_DMA_PASSES=0; else unset KDET_FCL_DMA_PASSES; fi
  timeout $(( $(left) - 5 )) build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 \
    --no-kfree --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only $3 \
    --out $W/bench-$2 > $W/bench-$2.log 2>&1
  echo "kdet_bench $2 rc=$?" >> $T
  python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-$2/bench.json > $W/table-$2.md 2>&1
  unset KDET_FCL_DMA_PASSES
}
for r in 1 2; do
  for k in 0 new; do
    if [ $(left) -lt 70 ]; then echo "part1 $k $r skipped (time)" >> $T; continue; fi
    bench $k p1-$k-$r unc,cloth
  done
done
date >> $T
B=build-gpu/tests
timeout 60 $B/test_cuda_upload > $W/t-upload.txt 2>&1; echo "test_cuda_upload rc=$?" >> $T
timeout 90 $B/test_cuda_query > $W/t-query.txt 2>&1; echo "test_cuda_query rc=$?" >> $T
for f in $W/t-*.txt; do tail -n 3 $f >> $T; done
for k in 0 new; do
  if [ $(left) -lt 50 ]; then echo "part2 $k skipped (time)" >> $T; continue; fi
  bench $k p2-$k fracture,nbody,chair
done
date >> $T
tar czf $OUT/out.tgz -C $W .
cp $W/table-*.md $OUT/ 2>/dev/null
