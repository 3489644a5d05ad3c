#!/bin/bash
# Device call 2 (carry .fcl-debs and .gpu-data; 600 s): the counting build up to 300k triangles
# (kCountBuildMaxTriangles). Builds gpu_bench (cmake as scripts/gpu_check.sh); ncu's kernel
# durations (clocks unlocked) of the 200k and 1M cloths and the cloth ball, summed per frame by
# gpu-h100-profile/kernels_per_frame.py; then, for the 200k cloth's query kernels only, the share
# of the kernel's time its SMs were busy and the warps they held (tails and underfilled grids).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c2
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
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in cloth-200k cloth-1000k unc-cloth-ball-self; do
  left=$((480 - ($(date +%s) - START)))
  if [ $left -lt 30 ]; then echo "ncu $sc skipped (time)" >> $T; continue; fi
  rep=2; [ $sc = cloth-1000k ] && rep=1
  timeout $((left < 150 ? left : 150)) $NCU --clock-control none \
    --metrics gpu__time_duration.sum,launch__grid_size,launch__registers_per_thread \
    --csv --print-units base $B --no-fcl --no-cpu --repeats $rep --only $sc \
    > $W/dur-$sc.csv 2> $W/dur-$sc.err
  echo "ncu $sc rc=$?" >> $T
  echo "== $sc" >> $OUT/kernels.txt
  python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py $W/dur-$sc.csv >> $OUT/kernels.txt 2>&1
  gzip -c $W/dur-$sc.csv > $OUT/dur-$sc.csv.gz
done
date >> $T
left=$((570 - ($(date +%s) - START)))
if [ $left -gt 30 ]; then
  timeout $((left - 5)) $NCU --clock-control none --kernel-name regex:"Candidates|CellPairs|planeFilter|Exact|orderPairs" \
    --launch-skip 60 --launch-count 24 \
    --metrics gpu__time_duration.sum,launch__grid_size,sm__cycles_active.avg.pct_of_peak_sustained_elapsed,sm__warps_active.avg.pct_of_peak_sustained_active \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 2 --only cloth-200k \
    > $W/busy-200k.csv 2> $W/busy-200k.err
  echo "ncu busy cloth-200k rc=$?" >> $T
  cp $W/busy-200k.csv $OUT/
fi
tar czf $OUT/logs.tgz -C $W build.log $(cd $W && ls *.err 2>/dev/null)
date >> $T
