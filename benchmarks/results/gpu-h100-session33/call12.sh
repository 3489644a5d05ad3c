#!/bin/bash
# Device call 12 (carry .fcl-debs and .gpu-data; 600 s): call 11's dynamic query slots kept only
# for the warp scans that test spans (call12-new.diff; the other kernels' PTX is unchanged),
# against the tree before (the diff reversed in a copy). Builds both (gpu_bench;
# test_cuda_query for the new tree); all of test_cuda_query on the new tree, also with spans
# always on and 1 or 32 lanes per query; gpu_bench GPU only, three rounds of the two trees in
# turn; ncu's durations, shared-memory configuration and L1 hit rates of phase 1 (cloth ball).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c12
mkdir -p $W /tmp/old
tar cf - --exclude=./build-gpu . | tar xf - -C /tmp/old
(cd /tmp/old && patch -R -p1 < benchmarks/results/gpu-h100-session33/call12-new.diff > $W/patch.log 2>&1)
echo "patch rc=$?" >> $T
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
timeout 200 build-gpu/tests/test_cuda_query > $W/tests-all.log 2>&1
echo "test_cuda_query (all) rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/tests-all.log >> $T
for P in 1 32; do
  KDET_FCL_CUDA_SPANS=1 KDET_FCL_CUDA_WARP_LANES=$P timeout 200 build-gpu/tests/test_cuda_query > $W/tests-lanes$P.log 2>&1
  echo "test_cuda_query (all; spans on, KDET_FCL_CUDA_WARP_LANES=$P) rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/tests-lanes$P.log >> $T
done
date >> $T
bin() { case $1 in old) echo /tmp/old/build-old/benchmarks/gpu_bench;;
  span) echo /tmp/span/build-span/benchmarks/gpu_bench;; *) echo build-gpu/benchmarks/gpu_bench;; esac; }
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
  timeout 100 $NCU --clock-control none --kernel-name-base demangled \
    --kernel-name regex:'kdet_fcl::cuda.*(CandidatesWarp|CellPairs)' \
    --metrics gpu__time_duration.sum,smsp__inst_executed.sum,launch__registers_per_thread,launch__shared_mem_config_size,l1tex__t_sector_hit_rate.pct \
    --csv --print-units base $(bin $C) --no-fcl --no-cpu --repeats 5 --only unc-cloth-ball-self >> $W/ncu.csv 2> $W/ncu-$C.err
  echo "ncu $C rc=$?" >> $T
done
gzip -c $W/ncu.csv > $OUT/ncu.csv.gz
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err)
date >> $T
