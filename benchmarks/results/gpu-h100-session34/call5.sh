#!/bin/bash
# Device call 5 (carry .fcl-debs and .gpu-data; 600 s): the exact kernels' items spread one per
# warp before filling lanes (spreadIndex; call5-new.diff) against the committed tree (62aaaa8,
# the diff reversed). test_cuda_query on the new tree; gpu_bench GPU only, three rounds of the two
# trees in turn; ncu's durations of the exact kernels.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
R=benchmarks/results/gpu-h100-session34
W=/tmp/c5
mkdir -p $W /tmp/old
tar cf - --exclude=./build-gpu . | tar xf - -C /tmp/old
(cd /tmp/old && patch -R -p1 < $R/call5-new.diff > $W/patch-old.log 2>&1); echo "patch old rc=$?" >> $T
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
conf() {  # source dir, build dir, targets
  cmake -S $1 -B $2 -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
    -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
    -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
    "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
    -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/$(basename $2).log 2>&1
  cmake --build $2 --parallel 8 --target $3 >> $W/$(basename $2).log 2>&1
  echo "build $2 rc=$?" >> $T
}
conf . build-gpu "test_cuda_query gpu_bench" &
conf /tmp/old /tmp/old/build-old "gpu_bench" &
wait
date >> $T
timeout 100 build-gpu/tests/test_cuda_query > $W/query-all.log 2>&1
echo "test_cuda_query rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/query-all.log | head -8 >> $T
date >> $T
bin() { case $1 in new) echo build-gpu/benchmarks/gpu_bench;; *) echo /tmp/old/build-old/benchmarks/gpu_bench;; esac; }
r=0
for round in 1 2 3; do
  for C in old new; do
    r=$((r + 1))
    timeout 60 $(bin $C) --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --only unc-n-body \
      --only unc-funnel --only cloth-20k --only cloth-90k --only cloth-1000k \
      --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r ($C) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,tree,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$C,/" >> $OUT/bench.csv
  done
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in unc-cloth-ball-self cloth-90k unc-n-body-self; do
  for C in old new; do
    left=$((380 - ($(date +%s) - START)))
    if [ $left -lt 25 ]; then echo "ncu $sc $C skipped (time)" >> $T; continue; fi
    echo "== $sc $C" >> $W/ncu.csv
    timeout $((left - 5)) $NCU --clock-control none --kernel-name-base demangled \
      --kernel-name regex:'kdet_fcl::cuda.*Exact' \
      --metrics gpu__time_duration.sum,launch__grid_size,launch__registers_per_thread \
      --csv --print-units base $(bin $C) --no-fcl --no-cpu --repeats 3 --only $sc >> $W/ncu.csv 2> $W/ncu-$sc-$C.err
    echo "ncu $sc $C rc=$?" >> $T
  done
done
gzip -c $W/ncu.csv > $OUT/ncu.csv.gz
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err 2>/dev/null)
date >> $T
