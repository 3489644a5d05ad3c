#!/bin/bash
# Device call 4 (carry .fcl-debs/root and .gpu-data): updateVertices copying the positions to the
# device as it writes them (the same copy as commitVertices'). The CPU test of the pieces, the
# GPU tests of both calls; the frame probe (UPDATE=copy: updateVertices from a buffer filled
# untimed) with the copy against KDET_FCL_CUDA_COMMIT_COPY=0 and a placebo, twice, and once in
# the commit's form (the refactored check); kdet_bench --gpu-update copy on the UNC and cloth
# scenes; ctest -L cuda.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s43c4
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
P=benchmarks/results/gpu-session42  # the frame probe of session 42 (UPDATE=copy added)
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 $P/frame_probe.cpp \
  benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath \
  -Wl,--allow-shlib-undefined -o $W/probe > $W/probe-build.log 2>&1
echo "probe build rc=$? $(date +%T)" >> $T
SC="unc-cloth-ball unc-funnel unc-n-body cloth-20k cloth-40k cloth-90k cloth-200k cloth-250k cloth-1000k chair"
F="base;KDET_FCL_CUDA_COMMIT_COPY=0;KDET_FCL_CUDA_TILE=8"
UPDATE=copy FORMS="$F" ROUNDS=13 timeout 200 $W/probe $SC > $W/probe-update.txt 2>&1
echo "probe update rc=$? $(date +%T)" >> $T
UPDATE=copy FORMS="$F" ROUNDS=13 timeout 200 $W/probe $SC > $W/probe-update2.txt 2>&1
echo "probe update 2 rc=$? $(date +%T)" >> $T
FORMS="$F" ROUNDS=13 timeout 200 $W/probe $SC > $W/probe-commit.txt 2>&1
echo "probe commit rc=$? $(date +%T)" >> $T
wait $BG
build-gpu/tests/test_commit_copy > $W/test-commit-copy.txt 2>&1
echo "test_commit_copy rc=$? $(date +%T)" >> $T
timeout 110 build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree \
  --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only unc,cloth --gpu-update copy \
  --out $W/bench-copy > $W/bench-copy.log 2>&1
echo "kdet_bench copy rc=$? $(date +%T)" >> $T
python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-copy/bench.json > $W/table-copy.md 2>&1
(cd build-gpu && timeout 200 ctest -L cuda --output-on-failure > $W/ctest-cuda.txt 2>&1)
echo "ctest -L cuda rc=$? $(date +%T)" >> $T
tail -n 4 $W/ctest-cuda.txt >> $T
date >> $T
cp $W/probe-update.txt $W/probe-update2.txt $W/probe-commit.txt $W/table-copy.md $W/ctest-cuda.txt $OUT/
tar czf $OUT/out.tgz -C $W --exclude=probe --exclude='bench-*' .
