#!/bin/bash
# Device call 1 (carry .fcl-debs/root and .gpu-data): the tree with commitVertices copying the
# positions while it checks them (startCommitCopy, KDET_FCL_CUDA_COMMIT_COPY).
# The CUDA tests (ctest -L cuda) and the new CPU test; the frame probe, the copy on (default)
# against KDET_FCL_CUDA_COMMIT_COPY=0 and a placebo knob, profiling off and on; kdet_bench's GPU
# table on every deforming scene group.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
nproc >> $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s43c1
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
echo "lib rc=$? $(date +%T)" >> $T
(cmake --build build-gpu --parallel 12 --target kdet_bench test_cuda_device test_cuda_query \
  test_cuda_bvh test_cuda_upload test_cuda_box_test test_cuda_warp_search test_cuda_predicates \
  test_commit_copy > $W/build2.log 2>&1; echo "bench+test build rc=$? $(date +%T)" >> $T) &
BG=$!
P=benchmarks/results/gpu-session42  # the frame probe of session 42, unchanged
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 $P/frame_probe.cpp \
  benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath \
  -Wl,--allow-shlib-undefined -o $W/probe > $W/probe-build.log 2>&1
echo "probe build rc=$? $(date +%T)" >> $T
SC="unc-cloth-ball unc-funnel unc-n-body cloth-20k cloth-40k cloth-90k cloth-200k cloth-250k cloth-1000k nbody-181k chair"
F="base;KDET_FCL_CUDA_COMMIT_COPY=0;KDET_FCL_CUDA_TILE=8"
FORMS="$F" ROUNDS=12 timeout 200 $W/probe $SC > $W/probe-off.txt 2>&1
echo "probe off rc=$? $(date +%T)" >> $T
PROFILE=1 FORMS="$F" ROUNDS=8 timeout 200 $W/probe $SC > $W/probe-on.txt 2>&1
echo "probe on rc=$? $(date +%T)" >> $T
wait $BG
build-gpu/tests/test_commit_copy > $W/test-commit-copy.txt 2>&1
echo "test_commit_copy rc=$? $(date +%T)" >> $T
build-gpu/tests/test_cuda_query --gtest_filter='*Commit*:*Knob*' > $W/test-commit.txt 2>&1
echo "commit tests rc=$? $(date +%T)" >> $T
for part in 1 2; do
  if [ $part = 1 ]; then only=unc,cloth; else only=fracture,nbody,chair; fi
  timeout 110 build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree \
    --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only $only --out $W/bench-$part \
    > $W/bench-$part.log 2>&1
  echo "kdet_bench $part rc=$? $(date +%T)" >> $T
  python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-$part/bench.json > $W/table-$part.md 2>&1
done
(cd build-gpu && timeout 200 ctest -L cuda --output-on-failure > $W/ctest-cuda.txt 2>&1)
echo "ctest -L cuda rc=$? $(date +%T)" >> $T
tail -n 4 $W/ctest-cuda.txt >> $T
date >> $T
cp $W/probe-*.txt $W/table-*.md $W/ctest-cuda.txt $W/test-*.txt $OUT/
tar czf $OUT/out.tgz -C $W --exclude=probe --exclude='bench-*' .
tar czf $OUT/bench-json.tgz -C $W bench-1/bench.json bench-2/bench.json
