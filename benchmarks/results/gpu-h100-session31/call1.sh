#!/bin/bash
# Device call 1 (carry .fcl-debs and .gpu-data; 600 s): what the cloth ball's plane filter waits on.
# Builds gpu_bench; gpu_bench GPU only on the cloth ball (two processes, each filter setting:
# KDET_FCL_CUDA_FILTER_DECIDES 1 and 0); ncu's full set and SASS source counters of one
# planeFilterKernel launch and one selfExactKernel launch of the cloth ball (a warm frame).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c1
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
for round in 1 2; do
  for FD in 1 0; do
    r=$((r + 1))
    KDET_FCL_CUDA_FILTER_DECIDES=$FD timeout 45 $B --no-fcl --no-cpu --repeats 20 \
      --only unc-cloth-ball-self --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r (decides $FD) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,decides,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$FD,/" >> $OUT/bench.csv
  done
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for K in planeFilterKernel selfExactKernel; do
  timeout 150 $NCU --set full --import-source no --kernel-name regex:$K --launch-skip 4 --launch-count 1 \
    --print-details all --print-units base $B --no-fcl --no-cpu --repeats 10 \
    --only unc-cloth-ball-self > $W/ncu-$K.txt 2> $W/ncu-$K.err
  echo "ncu $K rc=$?" >> $T
  timeout 150 $NCU --section SourceCounters --kernel-name regex:$K --launch-skip 4 --launch-count 1 \
    --page source --print-source sass --csv $B --no-fcl --no-cpu --repeats 10 \
    --only unc-cloth-ball-self > $W/sass-$K.csv 2> $W/sass-$K.err
  echo "ncu sass $K rc=$?" >> $T
  date >> $T
done
tar czf $OUT/ncu.tgz -C $W $(cd $W && ls ncu-* sass-*)
tar czf $OUT/logs.tgz -C $W build.log bench.log
date >> $T
