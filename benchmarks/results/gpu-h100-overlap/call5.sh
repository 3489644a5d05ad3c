#!/bin/bash
# Device call 5 (carry .fcl-debs and .gpu-data; 600 s): call 4 saw the cloth ball's candidate
# search at 0.21 ms in most processes against call 1's 0.17: which of the two kernels the SMs
# take first is left to the hardware. An experimental KDET_FCL_CUDA_SELF_OVERLAP (this call
# only): 0 apart; 1 the side stream of default priority (call 1); 2 the cells' kernel on a side
# stream of the greatest priority; 3 the scan there instead. Three rounds in turn, gpu_bench GPU
# only, 20 repeats, on the scenes that take the cells. Then the small meshes below the cells'
# rule (the funnel, the 2k and 4k cloths of --quick, the 20k and 40k cloths) with the cells
# forced (KDET_FCL_CUDA_SELF_CELLS=1, mode 2) against the default, three rounds.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c5
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
  for V in 0 1 2 3; do
    r=$((r + 1))
    KDET_FCL_CUDA_SELF_OVERLAP=$V timeout 40 $B --no-fcl --no-cpu --repeats 20 \
      --only unc-cloth-ball --only unc-n-body --only cloth-200k --only cloth-1000k \
      --csv $W/a-$r.csv >> $W/bench-a.log 2>&1
    echo "A round $round (overlap $V) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/a-1.csv | sed 's/^/round,overlap,/' > $OUT/modes.csv; fi
    tail -n +2 $W/a-$r.csv | sed "s/^/$round,$V,/" >> $OUT/modes.csv
  done
done
date >> $T
r=0
for round in 1 2 3; do
  for V in "" 1; do
    left=$((585 - ($(date +%s) - START)))
    if [ $left -lt 40 ]; then echo "B round $round cells '$V' skipped (time)" >> $T; continue; fi
    r=$((r + 1))
    KDET_FCL_CUDA_SELF_OVERLAP=2 KDET_FCL_CUDA_SELF_CELLS=$V timeout 30 $B --no-fcl --no-cpu \
      --repeats 20 --only unc-funnel --only cloth-20k --only cloth-40k \
      --csv $W/b-$r.csv >> $W/bench-b.log 2>&1
    echo "B round $round (cells '$V') rc=$?" >> $T
    KDET_FCL_CUDA_SELF_OVERLAP=2 KDET_FCL_CUDA_SELF_CELLS=$V timeout 30 $B --no-fcl --no-cpu \
      --quick --repeats 20 --only cloth-2k --only cloth-4k \
      --csv $W/q-$r.csv >> $W/bench-b.log 2>&1
    echo "B round $round quick (cells '$V') rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/b-1.csv | sed 's/^/round,cells,/' > $OUT/cells.csv; fi
    tail -n +2 $W/b-$r.csv | sed "s/^/$round,x$V,/" >> $OUT/cells.csv
    tail -n +2 $W/q-$r.csv | sed "s/^/$round,x$V,/" >> $OUT/cells.csv
  done
done
tar czf $OUT/logs.tgz -C $W build.log bench-a.log bench-b.log
date >> $T
