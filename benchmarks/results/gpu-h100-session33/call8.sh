#!/bin/bash
# Device call 8 (carry .fcl-debs and .gpu-data; 600 s): with the queue of seen entries (tree
# 3eee3f8), the crowded scenes' phase-1 shapes again: lanes per query of the warp scan
# (KDET_FCL_CUDA_WARP_LANES: by default 8 where the density exceeds 4; 4, 16) and rows per task
# of the cells' pairs (KDET_FCL_CUDA_CELL_ROWS: by default 8 there; 16, 32). gpu_bench GPU only,
# three rounds of the five settings in turn, one process each.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
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
  for C in default lanes4 lanes16 rows16 rows32; do
    r=$((r + 1))
    case $C in
      default) E="KDET_FCL_CUDA_WARP_LANES=";;
      lanes4) E="KDET_FCL_CUDA_WARP_LANES=4";;
      lanes16) E="KDET_FCL_CUDA_WARP_LANES=16";;
      rows16) E="KDET_FCL_CUDA_CELL_ROWS=16";;
      rows32) E="KDET_FCL_CUDA_CELL_ROWS=32";;
    esac
    timeout 80 env $E $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball \
      --only unc-funnel-2frames --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r ($C) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,tree,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$C,/" >> $OUT/bench.csv
  done
done
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log)
date >> $T
