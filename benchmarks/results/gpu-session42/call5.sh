#!/bin/bash
# Device call 5 (carry .fcl-debs/root and .gpu-data): the final tree (code as in call 3, comments
# since): kdet_bench's GPU table twice more on the UNC and cloth scenes and once more on the
# fracture, n-body and chair scenes, with the LBVH in the same process.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s42c5
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
echo "build rc=$? $(date +%T)" >> $T
for run in 1a 2 1b; do
  if [ ${run:0:1} = 1 ]; then only=unc,cloth; else only=fracture,nbody,chair; fi
  timeout 110 build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree \
    --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only $only --out $W/bench-$run \
    > $W/bench-$run.log 2>&1
  echo "kdet_bench $run rc=$? $(date +%T)" >> $T
  python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-$run/bench.json > $W/table-$run.md 2>&1
done
date >> $T
cp $W/table-*.md $OUT/
tar czf $OUT/bench-json.tgz -C $W bench-1a/bench.json bench-1b/bench.json bench-2/bench.json
