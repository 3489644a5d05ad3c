#!/bin/bash
# Device call 8 (carry .fcl-debs and .gpu-data; 600 s): the two cloth-ball frames (joint) still
# run their cells' kernel and their scan apart: their 3.8M candidates exceed the round limit (14
# per triangle), and the rounds of a self query's stages run one kernel each. Three forms, three
# rounds in turn, gpu_bench GPU only, 20 repeats: the default (the stages' rounds); one round
# (KDET_FCL_CUDA_ROUND_CANDIDATES=0: both kernels at once, more memory); rounds that split both
# kernels' tasks, each round running both at once (experimental KDET_FCL_CUDA_STAGED_ROUNDS=0).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c8
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target gpu_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for round in 1 2 3; do
  for V in stages one split; do
    r=$((r + 1))
    case $V in
      stages) E="" ;;
      one) E="KDET_FCL_CUDA_ROUND_CANDIDATES=0" ;;
      split) E="KDET_FCL_CUDA_STAGED_ROUNDS=0" ;;
    esac
    env $E timeout 40 $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball \
      --csv $W/a-$r.csv >> $W/bench.log 2>&1
    echo "round $round ($V) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/a-1.csv | sed 's/^/round,form,/' > $OUT/forms.csv; fi
    tail -n +2 $W/a-$r.csv | sed "s/^/$round,$V,/" >> $OUT/forms.csv
  done
done
tar czf $OUT/logs.tgz -C $W build.log bench.log
date >> $T
