#!/bin/bash
# Device call 4 (carry .fcl-debs and .gpu-data; 600 s): the committed change (4ea2982). The full
# run with every peer in one process (gpu_bench --big --repeats 10); the cloth ball in twelve
# processes; then the two cloth-ball frames' read-back (445,614 pairs, 13.6 chunks) under the
# forecast with 128 KiB and 1 MiB read-back chunks, with 8 copy threads, and with the forecast
# off, three rounds in turn.
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
left=$((440 - ($(date +%s) - START)))
timeout $left $B --big --repeats 10 --csv $OUT/gpu_bench.csv --json $OUT/gpu_bench.json \
  --md $OUT/gpu_bench.md > $W/gpu_bench.log 2>&1
echo "full run rc=$?" >> $T
date >> $T
for r in $(seq 1 12); do
  left=$((480 - ($(date +%s) - START)))
  if [ $left -lt 10 ]; then echo "process $r skipped (time)" >> $T; break; fi
  timeout $left $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball-self --csv $W/p-$r.csv >> $W/twelve.log 2>&1
  echo "process $r rc=$?" >> $T
  if [ $r = 1 ]; then head -1 $W/p-1.csv | sed 's/^/process,/' > $OUT/twelve.csv; fi
  tail -n +2 $W/p-$r.csv | sed "s/^/$r,/" >> $OUT/twelve.csv
done
date >> $T
r=0
for round in 1 2 3; do
  for C in default c128k c1m t8 off; do
    left=$((585 - ($(date +%s) - START)))
    if [ $left -lt 10 ]; then echo "probe $round $C skipped (time)" >> $T; continue; fi
    r=$((r + 1))
    case $C in
      default) E=();;
      c128k) E=(KDET_FCL_CUDA_DOWNLOAD_CHUNK=131072);;
      c1m) E=(KDET_FCL_CUDA_DOWNLOAD_CHUNK=1048576);;
      t8) E=(KDET_FCL_CUDA_DOWNLOAD_THREADS=8);;
      off) E=(KDET_FCL_CUDA_ONE_TRIP_FORECAST=0);;
    esac
    timeout $left env "${E[@]}" $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball-2frames \
      --csv $W/probe-$r.csv >> $W/probe.log 2>&1
    echo "probe $round $C rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/probe-1.csv | sed 's/^/round,setting,/' > $OUT/probe.csv; fi
    tail -n +2 $W/probe-$r.csv | sed "s/^/$round,$C,/" >> $OUT/probe.csv
  done
done
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log)
date >> $T
