#!/bin/bash
# Device call 2 (carry .fcl-debs and .gpu-data; 600 s): exact zeros in the plane filter's last
# step (call2-filter.diff) and the exact orientations' short sums in registers
# (exact::orient3dSignShort), with the exact kernels' grid at the resident blocks
# (call2-grid.diff); the whole change is call2-new.diff. Four trees: new (the working tree), old
# (call2-new.diff reversed), nogrid (call2-grid.diff reversed), filter (old + call2-filter.diff).
# The new device test and test_cuda_query on new; gpu_bench GPU only, three rounds of the four
# trees in turn; ncu's durations of the filter and exact kernels.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
R=benchmarks/results/gpu-h100-session34
W=/tmp/c2
mkdir -p $W /tmp/old /tmp/nogrid /tmp/filter
for d in /tmp/old /tmp/nogrid /tmp/filter; do tar cf - --exclude=./build-gpu . | tar xf - -C $d; done
(cd /tmp/old && patch -R -p1 < $R/call2-new.diff > $W/patch-old.log 2>&1); echo "patch old rc=$?" >> $T
(cd /tmp/nogrid && patch -R -p1 < $R/call2-grid.diff > $W/patch-nogrid.log 2>&1); echo "patch nogrid rc=$?" >> $T
(cd /tmp/filter && patch -R -p1 < $R/call2-new.diff > $W/patch-filter.log 2>&1 && patch -p1 < $R/call2-filter.diff >> $W/patch-filter.log 2>&1); echo "patch filter rc=$?" >> $T
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
conf() {  # source dir, build dir, targets
  cmake -S $1 -B $2 -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
    -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
    -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
    "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
    -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/$(basename $2).log 2>&1
  cmake --build $2 --parallel 4 --target $3 >> $W/$(basename $2).log 2>&1
  echo "build $2 rc=$?" >> $T
}
conf . build-gpu "test_cuda_query test_cuda_predicates gpu_bench" &
conf /tmp/old /tmp/old/build-old "gpu_bench" &
conf /tmp/nogrid /tmp/nogrid/build-nogrid "gpu_bench" &
conf /tmp/filter /tmp/filter/build-filter "gpu_bench" &
wait
date >> $T
t() {  # name, timeout, env..., binary and args
  local name=$1 to=$2; shift 2
  timeout $to env "$@" > $W/$name.log 2>&1
  echo "$name rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED|SKIPPED) |^\[  FAILED" $W/$name.log | head -8 >> $T
}
t predicates 60 build-gpu/tests/test_cuda_predicates
t query-all 200 build-gpu/tests/test_cuda_query
date >> $T
bin() { case $1 in new) echo build-gpu/benchmarks/gpu_bench;; *) echo /tmp/$1/build-$1/benchmarks/gpu_bench;; esac; }
r=0
for round in 1 2 3; do
  for C in old new nogrid filter; do
    r=$((r + 1))
    timeout 60 $(bin $C) --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --only unc-n-body \
      --only unc-funnel --only cloth-20k --only cloth-90k --only cloth-250k --only cloth-1000k \
      --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r ($C) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,tree,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$C,/" >> $OUT/bench.csv
  done
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in cloth-90k unc-n-body-self unc-cloth-ball-self cloth-1000k; do
  for C in old new nogrid filter; do
    left=$((580 - ($(date +%s) - START)))
    if [ $left -lt 25 ]; then echo "ncu $sc $C skipped (time)" >> $T; continue; fi
    echo "== $sc $C" >> $W/ncu.csv
    timeout $((left - 5)) $NCU --clock-control none --kernel-name-base demangled \
      --kernel-name regex:'kdet.*(Exact|planeFilter)' \
      --metrics gpu__time_duration.sum,launch__grid_size,launch__registers_per_thread \
      --csv --print-units base $(bin $C) --no-fcl --no-cpu --repeats 3 --only $sc >> $W/ncu.csv 2> $W/ncu-$sc-$C.err
    echo "ncu $sc $C rc=$?" >> $T
  done
done
gzip -c $W/ncu.csv > $OUT/ncu.csv.gz
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err 2>/dev/null)
date >> $T
