#!/bin/bash
# Device call 6 (carry .fcl-debs and .gpu-data; 600 s): the final form (call 5): the scan queued
# first on a side stream of the greatest priority, the cells' kernel then on the query's stream;
# with the overlap on (default) every self query takes the cells' pairs.
# A: the new defaults against KDET_FCL_CUDA_SELF_OVERLAP=0 (the cells' kernel, then the scan; the
#    cells only from 203k entries, the rule before), three rounds in turn.
# B: with the overlap, the cells against no cells (KDET_FCL_CUDA_SELF_CELLS=0) on the meshes
#    below the old rule, three rounds in turn (the 2k and 4k cloths of --quick too).
# Then the full gpu_bench run with every peer in one process (--big --repeats 10).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c6
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
  for V in "" 0; do
    r=$((r + 1))
    KDET_FCL_CUDA_SELF_OVERLAP=$V timeout 45 $B --no-fcl --no-cpu --repeats 20 \
      --only unc-cloth-ball --only unc-n-body --only unc-funnel --only cloth-20k --only cloth-40k \
      --only cloth-90k --only cloth-200k --only cloth-1000k --csv $W/a-$r.csv >> $W/bench-a.log 2>&1
    echo "A round $round (overlap '$V') rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/a-1.csv | sed 's/^/round,overlap,/' > $OUT/overlap.csv; fi
    tail -n +2 $W/a-$r.csv | sed "s/^/$round,x$V,/" >> $OUT/overlap.csv
  done
done
date >> $T
r=0
for round in 1 2 3; do
  for V in "" 0; do
    r=$((r + 1))
    KDET_FCL_CUDA_SELF_CELLS=$V timeout 30 $B --no-fcl --no-cpu --repeats 20 \
      --only unc-funnel --only cloth-20k --only cloth-40k --csv $W/b-$r.csv >> $W/bench-b.log 2>&1
    echo "B round $round (cells '$V') rc=$?" >> $T
    KDET_FCL_CUDA_SELF_CELLS=$V timeout 30 $B --no-fcl --no-cpu --quick --repeats 20 \
      --only cloth-2k --only cloth-4k --csv $W/q-$r.csv >> $W/bench-b.log 2>&1
    echo "B round $round quick (cells '$V') rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/b-1.csv | sed 's/^/round,cells,/' > $OUT/cells.csv; fi
    tail -n +2 $W/b-$r.csv | sed "s/^/$round,x$V,/" >> $OUT/cells.csv
    tail -n +2 $W/q-$r.csv | sed "s/^/$round,x$V,/" >> $OUT/cells.csv
  done
done
date >> $T
left=$((590 - ($(date +%s) - START)))
timeout $left $B --big --repeats 10 --csv $OUT/gpu_bench.csv --json $OUT/gpu_bench.json \
  --md $OUT/gpu_bench.md > $W/gpu_bench.log 2>&1
echo "full run rc=$?" >> $T
tar czf $OUT/logs.tgz -C $W build.log bench-a.log bench-b.log gpu_bench.log
date >> $T
