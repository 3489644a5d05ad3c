#!/bin/bash
# Device call 4 (carry .fcl-debs and .gpu-data; 600 s): with the cells' kernel beside the scan
# (call 1), are the rules tuned for the two kernels one after the other still right?
# A: the cells for the smaller meshes too (KDET_FCL_CUDA_SELF_CELLS=1 against the default, which
#    takes them from 48 x 32 entries per SM), on the funnel, the 20k-90k cloths and the n-body's
#    fracture-free scenes below the rule; three rounds in turn.
# B: entries per warp task of the cells' pairs (KDET_FCL_CUDA_CELL_ROWS = default, 8, 16, 32)
#    on the scenes that take the cells; three rounds in turn.
# gpu_bench GPU only, 20 repeats.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
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
for round in 1 2 3; do
  for V in "" 1; do
    r=$((r + 1))
    KDET_FCL_CUDA_SELF_CELLS=$V timeout 40 $B --no-fcl --no-cpu --repeats 20 \
      --only unc-funnel --only cloth-20k --only cloth-40k --only cloth-90k \
      --csv $W/a-$r.csv >> $W/bench-a.log 2>&1
    echo "A round $round (self cells '$V') rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/a-1.csv | sed 's/^/round,cells,/' > $OUT/cells.csv; fi
    tail -n +2 $W/a-$r.csv | sed "s/^/$round,x$V,/" >> $OUT/cells.csv
  done
done
date >> $T
r=0
for round in 1 2 3; do
  for V in "" 8 16 32; do
    left=$((585 - ($(date +%s) - START)))
    if [ $left -lt 40 ]; then echo "B round $round rows '$V' skipped (time)" >> $T; continue; fi
    r=$((r + 1))
    KDET_FCL_CUDA_CELL_ROWS=$V timeout 40 $B --no-fcl --no-cpu --repeats 20 \
      --only unc-cloth-ball --only unc-n-body --only cloth-200k --only cloth-1000k \
      --csv $W/b-$r.csv >> $W/bench-b.log 2>&1
    echo "B round $round (cell rows '$V') rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/b-1.csv | sed 's/^/round,rows,/' > $OUT/rows.csv; fi
    tail -n +2 $W/b-$r.csv | sed "s/^/$round,x$V,/" >> $OUT/rows.csv
  done
done
tar czf $OUT/logs.tgz -C $W build.log bench-a.log bench-b.log
date >> $T
