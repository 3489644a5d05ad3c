#!/bin/bash
# Device call 4 (carry .fcl-debs/root and .gpu-data): the tree with the DMA-friendly vertex passes
# (src/cpu/dma_passes.h). A/B in one build by the knob, KDET_FCL_DMA_PASSES=0 (the passes of
# before) against unset (the new rule), in alternating rounds:
#   - phase_probe.cpp (updateVertices, then the inter and self queries) on the 90k, 250k, 1M cloths;
#   - ../gpu-session39/fcl_gpu_probe.cpp (the FCL entry points' deformation path: a commit);
#   - kdet_bench's GPU form (commitVertices) on the UNC and cloth scenes with the GPU methods.
# Tests: test_dma_passes, HashedMesh, test_cuda_upload (also with the knob at 1), test_cuda_query.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
left() { echo $((580 - ($(date +%s) - START))); }
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s40c4
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L:$PWD/build-gpu
P=benchmarks/results/gpu-session40
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader > $W/gpu.txt 2>&1
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target kdet_fcl >> $W/build.log 2>&1
echo "lib build rc=$?" >> $T
(cmake --build build-gpu --parallel 12 --target kdet_bench test_cuda_query test_cuda_upload \
   test_hierarchy test_dma_passes >> $W/build.log 2>&1; echo "build rc=$?" >> $T) &
BP=$!
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 \
  $P/phase_probe.cpp benchmarks/bench_scenes.cpp \
  -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath -Wl,--allow-shlib-undefined -o $W/phase >> $W/build.log 2>&1
echo "phase build rc=$?" >> $T
g++ -O2 -std=c++17 -I include -isystem $D/usr/include -isystem $D/usr/include/x86_64-linux-gnu \
  -isystem /usr/include/eigen3 benchmarks/results/gpu-session39/fcl_gpu_probe.cpp \
  -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath -Wl,--allow-shlib-undefined -o $W/fclprobe >> $W/build.log 2>&1
echo "fcl probe build rc=$?" >> $T
wait $BP
date >> $T
# Probes, knob 0 / unset in turn (the builds are done: the host is quiet).
for r in 1 2 3; do
  for k in 0 new; do
    if [ $k = 0 ]; then export KDET_FCL_DMA_PASSES=0; else unset KDET_FCL_DMA_PASSES; fi
    echo "== $k round $r" >> $W/phase-$k.txt
    timeout 60 $W/phase cloth-90k cloth-250k cloth-1000k >> $W/phase-$k.txt 2>&1
    echo "phase $k $r rc=$?" >> $T
  done
done
for r in 1 2; do
  for k in 0 new; do
    if [ $k = 0 ]; then export KDET_FCL_DMA_PASSES=0; else unset KDET_FCL_DMA_PASSES; fi
    echo "== $k round $r" >> $W/fcl-$k.txt
    timeout 60 $W/fclprobe 40 0 >> $W/fcl-$k.txt 2>&1
    echo "fcl $k $r rc=$?" >> $T
  done
done
unset KDET_FCL_DMA_PASSES
date >> $T
B=build-gpu/tests
timeout 60 $B/test_dma_passes > $W/t-dma.txt 2>&1; echo "test_dma_passes rc=$?" >> $T
timeout 120 $B/test_hierarchy --gtest_filter='HashedMesh.*' > $W/t-hm.txt 2>&1; echo "HashedMesh rc=$?" >> $T
timeout 120 $B/test_cuda_upload > $W/t-upload.txt 2>&1; echo "test_cuda_upload rc=$?" >> $T
KDET_FCL_DMA_PASSES=1 timeout 120 $B/test_cuda_upload > $W/t-upload1.txt 2>&1; echo "test_cuda_upload knob 1 rc=$?" >> $T
timeout 240 $B/test_cuda_query > $W/t-query.txt 2>&1; echo "test_cuda_query rc=$?" >> $T
tail -3 $W/t-*.txt >> $T
date >> $T
for r in 1 2; do
  for k in 0 new; do
    if [ $(left) -lt 70 ]; then echo "kdet_bench $k $r skipped (time)" >> $T; continue; fi
    if [ $k = 0 ]; then export KDET_FCL_DMA_PASSES=0; else unset KDET_FCL_DMA_PASSES; fi
    timeout $(( $(left) - 10 )) build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 \
      --no-kfree --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only unc,cloth \
      --out $W/bench-$k-$r > $W/bench-$k-$r.log 2>&1
    echo "kdet_bench $k $r rc=$?" >> $T
    python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-$k-$r/bench.json > $W/table-$k-$r.md 2>&1
  done
done
unset KDET_FCL_DMA_PASSES
date >> $T
cp $W/phase-0.txt $W/phase-new.txt $OUT/ 2>/dev/null
tar czf $OUT/out.tgz -C $W --exclude=phase --exclude=fclprobe .
