#!/bin/bash
# Second device call (carry .fcl-debs and .gpu-data; 600 s): the tree with the warp scan's cell
# ranges from fixed-point coordinates and its lanes stepping straight to their share of the
# cells (KDET_FCL_CUDA_FIXED_CELLS), and the warp-wide candidate kernels' pairs staged in shared
# memory, 32 per atomic (KDET_FCL_CUDA_STAGE_PAIRS). Builds every CUDA test program and
# gpu_bench (-lineinfo); ctest -L cuda and the script's sanitizer pass; memcheck of the new
# fixed-point test; gpu_bench on the UNC scenes and the 90k, 250k and 1M cloths in six rounds
# alternating three configurations (both on; both off; fixed cells only), the 10M cloth once
# with both on and once with both off; then ncu's source counters for one launch each of the
# warp scan and the cells' pairs of the cloth ball's self query (both on).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 SANITIZER=1 CMAKE_ARGS="-DCMAKE_CUDA_FLAGS=-lineinfo" \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/chk/ctest.log | head -30 >> $T
grep -h "ERROR SUMMARY\|RACECHECK SUMMARY" /tmp/chk/sanitizer-*.log >> $T 2>/dev/null
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
timeout 120 $SAN --tool memcheck build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQueryTyped/0.FixedPointCell*' > /tmp/chk/memcheck-fixed.log 2>&1
echo "memcheck fixed rc=$?" >> $T; tail -2 /tmp/chk/memcheck-fixed.log >> $T
date >> $T
OFF="FIXED_CELLS=0 STAGE_PAIRS=0"
FIX="STAGE_PAIRS=0"
r=0
for C in "" "$OFF" "$FIX" "" "$OFF" "$FIX"; do
  r=$((r + 1))
  ENVS=""
  for kv in $C; do ENVS="$ENVS KDET_FCL_CUDA_$kv"; done
  env $ENVS timeout 100 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 \
    --only unc --only cloth-90k --only cloth-250k --only cloth-1000k \
    --csv /tmp/chk/bench-$r.csv >> /tmp/chk/bench.log 2>&1
  echo "bench round $r ('$C') rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/chk/bench-1.csv | sed 's/^/round,config,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/chk/bench-$r.csv | sed "s/^/$r,'$C',/" >> $OUT/bench.csv
done
date >> $T
for C in "" "$OFF"; do
  ENVS=""
  for kv in $C; do ENVS="$ENVS KDET_FCL_CUDA_$kv"; done
  env $ENVS timeout 100 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --big --only 10000k \
    --csv /tmp/chk/big.csv >> /tmp/chk/bench.log 2>&1
  echo "10M ('$C') rc=$?" >> $T
  tail -n +2 /tmp/chk/big.csv | sed "s/^/big,'$C',/" >> $OUT/bench.csv
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for K in selfCandidatesWarpKernel selfCellPairsKernel; do
  timeout 100 $NCU --set full --import-source yes -k regex:$K -s 10 -c 1 -o /tmp/chk/$K \
    build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 1 --only unc-cloth-ball-self \
    > /tmp/chk/ncu-$K.log 2>&1
  echo "ncu $K rc=$?" >> $T
  $NCU -i /tmp/chk/$K.ncu-rep --page source --csv --print-source sass > /tmp/chk/$K-sass.csv 2>&1
  $NCU -i /tmp/chk/$K.ncu-rep --page details >> /tmp/chk/details.txt 2>&1
done
tar czf $OUT/source.tgz -C /tmp/chk selfCandidatesWarpKernel-sass.csv selfCellPairsKernel-sass.csv \
  details.txt ncu-selfCandidatesWarpKernel.log ncu-selfCellPairsKernel.log
tar czf $OUT/logs.tgz -C /tmp/chk check.log ctest.log bench.log memcheck-fixed.log \
  $(cd /tmp/chk && ls sanitizer-*.log build.log 2>/dev/null)
date >> $T
