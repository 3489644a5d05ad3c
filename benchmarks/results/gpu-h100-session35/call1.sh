#!/bin/bash
# Device call 1 (carry .fcl-debs and .gpu-data; 600 s): what the host result's output costs on
# the tree of efed81f. gpu_bench GPU only on the UNC scenes and the 90k cloth, three rounds of:
# the default; KDET_FCL_CUDA_ONE_TRIP_COPY=0 (the order in the trip, no mapped copy: the pairs
# read back after the counts); KDET_FCL_CUDA_DOWNLOAD_THREADS=8. Then ncu's duration of the
# order's kernels on the cloth ball and the two cloth-ball frames, default and ONE_TRIP_COPY=0.
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
r=0
for round in 1 2 3; do
  for C in default copy0 threads8; do
    r=$((r + 1))
    case $C in
      default) E=();;
      copy0) E=(KDET_FCL_CUDA_ONE_TRIP_COPY=0);;
      threads8) E=(KDET_FCL_CUDA_DOWNLOAD_THREADS=8);;
    esac
    timeout 60 env "${E[@]}" $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball \
      --only unc-n-body --only unc-funnel --only cloth-90k --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r ($C) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,setting,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$C,/" >> $OUT/bench.csv
  done
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in unc-cloth-ball-self unc-cloth-ball-2frames; do
  for C in default copy0; do
    left=$((585 - ($(date +%s) - START)))
    if [ $left -lt 30 ]; then echo "ncu $sc $C skipped (time)" >> $T; continue; fi
    case $C in default) E=();; copy0) E=(KDET_FCL_CUDA_ONE_TRIP_COPY=0);; esac
    echo "== $sc $C" >> $W/ncu.csv
    timeout $((left - 10)) env "${E[@]}" $NCU --clock-control none --kernel-name-base demangled \
      --kernel-name regex:'(orderPairs|scatterPairs|rankPairs|copyPairsOut|unpackPairs|DeviceScan|DeviceRadix|Onesweep)' \
      --metrics gpu__time_duration.sum,launch__grid_size \
      --csv --print-units base $B --no-fcl --no-cpu --repeats 5 --only $sc >> $W/ncu.csv 2> $W/ncu-$sc-$C.err
    echo "ncu $sc $C rc=$?" >> $T
  done
done
gzip -c $W/ncu.csv > $OUT/ncu.csv.gz
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err 2>/dev/null)
date >> $T
