#!/bin/bash
# Device call 4 (carry .fcl-debs and .gpu-data; 600 s): the queue of seen entries (EntryRing)
# kept only in the kernels that test sub-cell spans (kQueueSeen; call4-new.diff), against the
# tree before (the diff reversed in a copy), and two mutants: the warp scan's last drain left
# out (mut-scan), the cells' drain at a task's end left out (mut-cells). Builds the four
# (gpu_bench, test_cuda_query, test_cuda_warp_search as needed); the new tests; all of
# test_cuda_query on the new tree, also with spans always on; the mutants on the span and
# cells tests with spans on; a mutant of the ring's slot mask (63 -> 31) on its own test;
# gpu_bench GPU only, three rounds of the two trees in turn; ncu's durations of phase 1.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c4
mkdir -p $W /tmp/old /tmp/ms /tmp/mc
for d in /tmp/old /tmp/ms /tmp/mc; do tar cf - --exclude=./build-gpu . | tar xf - -C $d; done
(cd /tmp/old && patch -R -p1 < benchmarks/results/gpu-h100-session33/call4-new.diff > $W/patch.log 2>&1)
echo "patch rc=$?" >> $T
sed -i 's|^    popRing(ring, ring.count, test);  // (the slots|    (void)0;  // (the slots|' /tmp/ms/cuda/device_hash.cuh
sed -i 's|^      popRing(ring, ring.count, test);  // (the rows|      (void)0;  // (the rows|' /tmp/mc/cuda/cuda_backend.cu
grep -c "(void)0;  // (the slots" /tmp/ms/cuda/device_hash.cuh >> $T
grep -c "(void)0;  // (the rows" /tmp/mc/cuda/cuda_backend.cu >> $T
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
conf . build-gpu "test_cuda_query test_cuda_warp_search gpu_bench" &
conf /tmp/old /tmp/old/build-old "gpu_bench" &
conf /tmp/ms /tmp/ms/build-ms "test_cuda_query" &
conf /tmp/mc /tmp/mc/build-mc "test_cuda_query" &
mkdir -p /tmp/mr && cp -r cuda include tests /tmp/mr/ && \
  sed -i 's/& 63u;/\& 31u;/' /tmp/mr/cuda/device_hash.cuh && \
  (grep -c "& 31u;" /tmp/mr/cuda/device_hash.cuh >> $T; \
   /usr/local/cuda/bin/nvcc -std=c++17 --generate-code=arch=compute_90,code=sm_90 -fmad=false \
   -I/tmp/mr -I/tmp/mr/include -I/tmp/mr/tests /tmp/mr/tests/test_cuda_warp_search.cu -lgtest \
   -lgtest_main -o /tmp/mr/ws > $W/mr.log 2>&1; echo "build mut-ring rc=$?" >> $T) &
wait
date >> $T
t() {  # name, env..., binary and args
  local name=$1; shift
  timeout 150 env "$@" > $W/$name.log 2>&1
  echo "$name rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED|SKIPPED) |^\[  FAILED" $W/$name.log | head -8 >> $T
}
t warp_search build-gpu/tests/test_cuda_warp_search
t mut-ring /tmp/mr/ws
t query-all build-gpu/tests/test_cuda_query
t query-spans KDET_FCL_CUDA_SPANS=1 build-gpu/tests/test_cuda_query
F='--gtest_filter=*Span*:*Cell*:*UNC*:*Unc*'
t mut-scan KDET_FCL_CUDA_SPANS=1 /tmp/ms/build-ms/tests/test_cuda_query $F
t mut-cells KDET_FCL_CUDA_SPANS=1 /tmp/mc/build-mc/tests/test_cuda_query $F
date >> $T
bin() { case $1 in old) echo /tmp/old/build-old/benchmarks/gpu_bench;; *) echo build-gpu/benchmarks/gpu_bench;; esac; }
r=0
for round in 1 2 3; do
  for C in old new; do
    r=$((r + 1))
    timeout 80 $(bin $C) --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --only unc-funnel \
      --only unc-n-body --only cloth-90k --only cloth-250k --only cloth-1000k --csv $W/bench-$r.csv \
      >> $W/bench.log 2>&1
    echo "bench $r ($C) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,tree,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$C,/" >> $OUT/bench.csv
  done
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for C in old new; do
  echo "== $C" >> $W/ncu.csv
  timeout 60 $NCU --clock-control none --kernel-name-base demangled \
    --kernel-name regex:'kdet_fcl::cuda.*(CandidatesWarp|CellPairs)' \
    --metrics gpu__time_duration.sum,smsp__inst_executed.sum,launch__registers_per_thread,sm__warps_active.avg.pct_of_peak_sustained_active \
    --csv --print-units base $(bin $C) --no-fcl --no-cpu --repeats 5 --only unc-cloth-ball \
    --only cloth-90k --only unc-n-body-2frames >> $W/ncu.csv 2> $W/ncu-$C.err
  echo "ncu $C rc=$?" >> $T
done
gzip -c $W/ncu.csv > $OUT/ncu.csv.gz
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err)
date >> $T
