#!/bin/bash
# Device call: vertex arrays from 256 KiB (was 1 MiB) copied by one DMA from their registered
# buffer (carry .fcl-debs and .gpu-data; 600 s). Builds test_cuda_query, test_cuda_upload and
# gpu_bench, runs their ctest -L cuda tests, then gpu_bench on the UNC scenes and the 90k cloth
# in four alternating rounds: the default, then KDET_FCL_CUDA_PIN_VERTICES=0 (every array staged:
# for arrays under 1 MiB, all of these but none else, the old behaviour). The funnel's 113 kB
# stays staged in both: the control. One CSV, the round and the knob in front.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 TARGETS="test_cuda_query test_cuda_upload gpu_bench" \
  scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/chk/ctest.log | head -30 >> $T
cp /tmp/chk/ctest.log $OUT/ctest.log 2>/dev/null
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
for r in 1 2 3 4; do
  if [ $((r % 2)) = 1 ]; then PIN=; else PIN=0; fi
  KDET_FCL_CUDA_PIN_VERTICES=$PIN timeout 100 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 \
    --only unc --only cloth-90k --csv /tmp/chk/bench-$r.csv >> $OUT/bench.log 2>&1
  echo "bench round $r (KDET_FCL_CUDA_PIN_VERTICES='$PIN') rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/chk/bench-1.csv | sed 's/^/round,pin,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/chk/bench-$r.csv | sed "s/^/$r,'$PIN',/" >> $OUT/bench.csv
done
date >> $T
