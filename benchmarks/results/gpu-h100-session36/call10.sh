#!/bin/bash
# Device call 10 (carry .fcl-debs and .gpu-data; 600 s): the final tree (17-bit segments by
# default). The two cloth-ball scenes in twelve processes, GPU only; then the full run with every
# peer in one process (gpu_bench --big --repeats 10).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c10
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
for r in $(seq 1 12); do
  left=$((300 - ($(date +%s) - START)))
  if [ $left -lt 10 ]; then echo "process $r skipped (time)" >> $T; break; fi
  timeout $left $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --csv $W/p-$r.csv >> $W/twelve.log 2>&1
  echo "process $r rc=$?" >> $T
  if [ $r = 1 ]; then head -1 $W/p-1.csv | sed 's/^/process,/' > $OUT/twelve.csv; fi
  tail -n +2 $W/p-$r.csv | sed "s/^/$r,/" >> $OUT/twelve.csv
done
date >> $T
left=$((590 - ($(date +%s) - START)))
if [ $left -gt 170 ]; then
  timeout $left $B --big --repeats 10 --csv $OUT/gpu_bench.csv --json $OUT/gpu_bench.json \
    --md $OUT/gpu_bench.md > $W/gpu_bench.log 2>&1
  echo "full run rc=$?" >> $T
else
  echo "full run skipped (time: $left s)" >> $T
fi
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log 2>/dev/null)
date >> $T
