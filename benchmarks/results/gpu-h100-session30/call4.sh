#!/bin/bash
# Device call 4 (carry .fcl-debs and .gpu-data; 600 s): a result written into the stage by the
# one trip, copied out by 1, 2 or 4 threads of the copy pool (KDET_FCL_CUDA_STAGE_COPY_THREADS,
# experimental, default 1). Builds gpu_bench; gpu_bench GPU only, three rounds of the three
# settings in turn, one process each, on the scenes whose results are 1 to 4 read-back chunks.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c4
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
for round in 1 2 3 4; do
  for K in 1 2 4; do
    r=$((r + 1))
    KDET_FCL_CUDA_STAGE_COPY_THREADS=$K timeout 60 $B --no-fcl --no-cpu --repeats 20 \
      --only unc-cloth-ball --only unc-funnel --only unc-n-body --only cloth-90k \
      --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r (stage copy threads $K) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,threads,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$K,/" >> $OUT/bench.csv
  done
done
date >> $T
tar czf $OUT/logs.tgz -C $W build.log bench.log
date >> $T
