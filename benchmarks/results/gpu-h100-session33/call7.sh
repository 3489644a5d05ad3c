#!/bin/bash
# Device call 7 (carry .fcl-debs and .gpu-data; 600 s): the copy out of the stage by threads
# armed before the trip (call7-new.diff; KDET_FCL_CUDA_STAGE_THREADS). Builds test_cuda_upload,
# test_cuda_query and gpu_bench; runs both test programs; gpu_bench GPU only, three rounds of
# KDET_FCL_CUDA_STAGE_THREADS = 1 (the copy before: one thread), 2, and unset (4) in turn, one
# process each; then the cloth ball in six processes of each of 1 and unset, alternating.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c7
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_upload test_cuda_query gpu_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
t() {  # name, env..., binary and args
  local name=$1; shift
  timeout 200 env "$@" > $W/$name.log 2>&1
  echo "$name rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED|SKIPPED) |^\[  FAILED" $W/$name.log | head -8 >> $T
}
t upload build-gpu/tests/test_cuda_upload
t query-all build-gpu/tests/test_cuda_query
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for round in 1 2 3; do
  for C in 1 2 unset; do
    r=$((r + 1))
    if [ $C = unset ]; then E="KDET_FCL_CUDA_STAGE_THREADS="; else E="KDET_FCL_CUDA_STAGE_THREADS=$C"; fi
    timeout 80 env $E $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --only unc-funnel \
      --only unc-n-body --only cloth-90k --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r ($C) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,tree,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$C,/" >> $OUT/bench.csv
  done
done
date >> $T
for r in $(seq 1 6); do
  for C in 1 unset; do
    left=$((560 - ($(date +%s) - START)))
    if [ $left -lt 10 ]; then echo "process $r $C skipped (time)" >> $T; break 2; fi
    if [ $C = unset ]; then E="KDET_FCL_CUDA_STAGE_THREADS="; else E="KDET_FCL_CUDA_STAGE_THREADS=$C"; fi
    timeout $left env $E $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball-self \
      --csv $W/p-$r-$C.csv >> $W/six.log 2>&1
    echo "process $r ($C) rc=$?" >> $T
    if [ ! -f $OUT/six.csv ]; then head -1 $W/p-$r-$C.csv | sed 's/^/process,tree,/' > $OUT/six.csv; fi
    tail -n +2 $W/p-$r-$C.csv | sed "s/^/$r,$C,/" >> $OUT/six.csv
  done
done
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log)
date >> $T
