#!/bin/bash
# Device call 2 (carry .fcl-debs and .gpu-data; 600 s): the register caps of the warp-wide
# phase 1 (KDET_FCL_CUDA_WARP_MINBLOCKS for the warp scans, KDET_FCL_CUDA_CELL_MINBLOCKS for the
# cells' pairs: 8, 10, 12 blocks per SM = 64, 48, 40 registers). Builds test_cuda_query and
# gpu_bench; the filter tests, then all of test_cuda_query under 12/12; gpu_bench GPU only in two
# rounds of six settings, one process each; ncu's durations of the phase-1 kernels on the cloth
# ball in each setting; ncu source counters of the cloth ball's exact kernel and a full set of
# the counting build's fill kernel (tree as is).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
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
cmake --build build-gpu --parallel 16 --target test_cuda_query gpu_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
timeout 100 build-gpu/tests/test_cuda_query --gtest_filter='*PlaneFilter*:*Rounds*' > $W/tests.log 2>&1
echo "test_cuda_query (filter, rounds) rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/tests.log >> $T
KDET_FCL_CUDA_WARP_MINBLOCKS=12 KDET_FCL_CUDA_CELL_MINBLOCKS=12 timeout 200 \
  build-gpu/tests/test_cuda_query > $W/tests-all.log 2>&1
echo "test_cuda_query (all; 12/12) rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) |^\[  FAILED" $W/tests-all.log >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for round in 1 2; do
  for C in 8/8 8/10 8/12 10/8 10/12 12/12; do
    r=$((r + 1))
    M=${C%/*}; Cm=${C#*/}
    KDET_FCL_CUDA_WARP_MINBLOCKS=$M KDET_FCL_CUDA_CELL_MINBLOCKS=$Cm timeout 80 $B --no-fcl \
      --no-cpu --repeats 20 --only unc-cloth-ball --only unc-funnel-2frames \
      --only unc-n-body-2frames --only cloth-90k --only cloth-1000k --csv $W/bench-$r.csv \
      >> $W/bench.log 2>&1
    echo "bench $r (warp $M, cells $Cm) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,warp,cells,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$M,$Cm,/" >> $OUT/bench.csv
  done
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for C in 8/8 8/12 10/12 12/12; do
  M=${C%/*}; Cm=${C#*/}
  echo "== warp $M cells $Cm" >> $W/ncu.csv
  KDET_FCL_CUDA_WARP_MINBLOCKS=$M KDET_FCL_CUDA_CELL_MINBLOCKS=$Cm timeout 100 $NCU \
    --clock-control none --kernel-name regex:'CandidatesWarp|CellPairs' \
    --metrics gpu__time_duration.sum,smsp__inst_executed.sum,launch__registers_per_thread,launch__grid_size,sm__warps_active.avg.pct_of_peak_sustained_active \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 5 --only unc-cloth-ball-self \
    >> $W/ncu.csv 2> $W/ncu-$M-$Cm.err
  echo "ncu warp $M cells $Cm rc=$?" >> $T
done
gzip -c $W/ncu.csv > $OUT/ncu.csv.gz
date >> $T
timeout 120 $NCU --clock-control none --kernel-name-base demangled \
  --kernel-name regex:'kdet_fcl::cuda.*selfExactKernel' --launch-skip 1 --launch-count 2 --section SourceCounters --page source --print-source sass --csv \
  $B --no-fcl --no-cpu --repeats 3 --only unc-cloth-ball-self > $W/exact-sass.csv 2> $W/exact-sass.err
echo "ncu exact sass rc=$?" >> $T
timeout 120 $NCU --clock-control none --kernel-name regex:'countFillKernel' --launch-skip 2 \
  --launch-count 1 --set full --print-details all \
  $B --no-fcl --no-cpu --repeats 3 --only unc-cloth-ball-self > $W/fill-full.txt 2> $W/fill-full.err
echo "ncu fill full rc=$?" >> $T
gzip -c $W/exact-sass.csv > $OUT/exact-sass.csv.gz
cp $W/fill-full.txt $OUT/
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log *.err)
date >> $T
