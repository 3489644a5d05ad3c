#!/bin/bash
# Third device call (carry .fcl-debs and .gpu-data; 600 s): the tree after call 2, with the
# fixed-point test's soup made denser (call 2: 8 self pairs, the test wants more than 10) and
# the span loads issued with the entry loads in the warp scan and the cells' pairs (no short
# circuit between the canonical-cell test and the span test). Builds every CUDA test program
# and gpu_bench (-lineinfo); ctest -L cuda and the script's sanitizer pass; memcheck of the
# fixed-point and cells' pairs tests, racecheck of the fixed-point test; gpu_bench on the UNC scenes and the 90k,
# 250k and 1M cloths in eight rounds alternating four configurations (both knobs on; both off;
# fixed cells only; staged pairs only), the 10M cloth once each with both on and both off; then
# ncu's source counters for the same launches of the warp scan and the cells' pairs as call 2.
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
for tool in memcheck racecheck; do
  F='CudaQueryTyped/0.FixedPointCell*'
  if [ $tool = memcheck ]; then F="$F:CudaQueryTyped/0.SelfPairsWithinALevel*"; fi
  timeout 120 $SAN --tool $tool --error-exitcode 3 build-gpu/tests/test_cuda_query \
    --gtest_filter="$F" > /tmp/chk/$tool-new.log 2>&1
  echo "$tool ($F) rc=$?" >> $T; tail -2 /tmp/chk/$tool-new.log >> $T
done
date >> $T
OFF="FIXED_CELLS=0 STAGE_PAIRS=0"
FIX="STAGE_PAIRS=0"
STG="FIXED_CELLS=0"
r=0
for C in "" "$OFF" "$FIX" "$STG" "" "$OFF" "$FIX" "$STG"; do
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
grep -E "^  [a-zA-Z_]|Duration|Executed Ipc A|Achieved Occ|Spilling Requests " /tmp/chk/details.txt >> $T
tar czf $OUT/source.tgz -C /tmp/chk selfCandidatesWarpKernel-sass.csv selfCellPairsKernel-sass.csv \
  details.txt ncu-selfCandidatesWarpKernel.log ncu-selfCellPairsKernel.log
tar czf $OUT/logs.tgz -C /tmp/chk check.log ctest.log bench.log memcheck-new.log racecheck-new.log \
  $(cd /tmp/chk && ls sanitizer-*.log build.log 2>/dev/null)
date >> $T
