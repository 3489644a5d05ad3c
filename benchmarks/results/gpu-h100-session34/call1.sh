#!/bin/bash
# Device call 1 (carry .fcl-debs and .gpu-data; 600 s): where the frames go on the current tree
# (b34a53f). Builds gpu_bench; gpu_bench GPU only on six scenes (two rounds); ncu's duration of
# every kernel of a few frames of the cloth ball, the 90k cloth, the n-body frame and the 1M
# cloth, summed per frame by kernels_per_frame.py.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
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
for r in 1 2; do
  timeout 90 $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --only unc-n-body \
    --only cloth-20k --only cloth-90k --only cloth-250k --only cloth-1000k --csv $W/bench-$r.csv \
    >> $W/bench.log 2>&1
  echo "bench $r rc=$?" >> $T
  if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,/' > $OUT/bench.csv; fi
  tail -n +2 $W/bench-$r.csv | sed "s/^/$r,/" >> $OUT/bench.csv
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in unc-cloth-ball-self cloth-90k unc-n-body-self cloth-1000k; do
  left=$((585 - ($(date +%s) - START)))
  if [ $left -lt 30 ]; then echo "ncu $sc skipped (time)" >> $T; continue; fi
  timeout $((left - 10)) $NCU --clock-control none \
    --metrics gpu__time_duration.sum,launch__grid_size,launch__registers_per_thread \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 3 --only $sc > $W/dur-$sc.csv 2> $W/dur-$sc.err
  echo "ncu $sc rc=$?" >> $T
  gzip -c $W/dur-$sc.csv > $OUT/dur-$sc.csv.gz
  echo "== $sc" >> $OUT/kernels.txt
  python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py $W/dur-$sc.csv >> $OUT/kernels.txt 2>&1
  date >> $T
done
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err 2>/dev/null)
date >> $T
