#!/bin/bash
# Device call 2 (carry .fcl-debs/root and .gpu-data): the tree with the knob check skipped for an
# unchanged setting and hardware_concurrency asked once. The check's cost (KNOBCOST=1); the
# frame probe with a placebo form (KDET_FCL_CUDA_TILE=8, the default's value) beside the defaults
# and KDET_FCL_CUDA_SPANS=1, profiling off and on; the knob tests; kdet_bench with the spans
# everywhere against the defaults.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s42c2
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
(cmake --build build-gpu --parallel 12 --target kdet_bench test_cuda_query > $W/build2.log 2>&1; echo "bench+test build rc=$? $(date +%T)" >> $T) &
BG=$!
P=benchmarks/results/gpu-session42
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 $P/frame_probe.cpp \
  benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath \
  -Wl,--allow-shlib-undefined -o $W/probe > $W/probe-build.log 2>&1
echo "probe build rc=$? $(date +%T)" >> $T
KNOBCOST=1 $W/probe > $W/probe-knobcost.txt 2>&1
SC="unc-cloth-ball unc-cloth-ball-pair unc-funnel unc-funnel-pair unc-n-body unc-n-body-pair cloth-20k cloth-90k cloth-200k cloth-250k cloth-1000k nbody-181k"
F="base;KDET_FCL_CUDA_TILE=8;KDET_FCL_CUDA_SPANS=1"
FORMS="$F" ROUNDS=10 timeout 200 $W/probe $SC > $W/probe-off.txt 2>&1
echo "probe off rc=$? $(date +%T)" >> $T
PROFILE=1 FORMS="$F" ROUNDS=10 timeout 200 $W/probe $SC > $W/probe-on.txt 2>&1
echo "probe on rc=$? $(date +%T)" >> $T
wait $BG
build-gpu/tests/test_cuda_query --gtest_filter='*Knob*' > $W/test-knobs.txt 2>&1
echo "knob tests rc=$? $(date +%T)" >> $T
for tag in base spans; do
  [ $tag = spans ] && export KDET_FCL_CUDA_SPANS=1
  timeout 110 build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree \
    --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only unc,cloth --out $W/bench-$tag \
    > $W/bench-$tag.log 2>&1
  echo "kdet_bench $tag rc=$? $(date +%T)" >> $T
  unset KDET_FCL_CUDA_SPANS
  python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-$tag/bench.json > $W/table-$tag.md 2>&1
done
date >> $T
cp $W/probe-*.txt $W/test-knobs.txt $W/table-*.md $OUT/
tar czf $OUT/out.tgz -C $W --exclude=probe .
