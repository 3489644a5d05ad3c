#!/bin/bash
# Fourth device call (carry .fcl-debs and .gpu-data; 600 s): the tree after call 3, with the
# cells' pairs' span load back behind the canonical-cell test (call 3's ncu: 102.3 against
# 98.0 us with it hoisted; the warp scan keeps its hoist: 159.7 against 171.2 us), the tests
# fixed for ctest's tile-scan run, and the staging of pairs extended to the plane filter and the
# exact tests (KDET_FCL_CUDA_STAGE_PAIRS now covers every kernel that emits a warp at a time).
# Builds every CUDA test program and gpu_bench; ctest -L cuda and the script's sanitizer pass;
# memcheck and racecheck of the fixed-point test and memcheck of the cells' pairs test;
# gpu_bench on the UNC scenes and the 90k, 250k and 1M cloths in six rounds alternating the
# default and KDET_FCL_CUDA_STAGE_PAIRS=0; the 10M cloth once each way.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 SANITIZER=1 \
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
OFF="STAGE_PAIRS=0"
r=0
for C in "" "$OFF" "" "$OFF" "" "$OFF"; do
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
tar czf $OUT/logs.tgz -C /tmp/chk check.log ctest.log bench.log memcheck-new.log racecheck-new.log \
  $(cd /tmp/chk && ls sanitizer-*.log build.log 2>/dev/null)
date >> $T
