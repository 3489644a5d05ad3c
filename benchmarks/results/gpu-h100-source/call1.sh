#!/bin/bash
# First device call of the session (carry .fcl-debs and .gpu-data; 600 s): the first GPU run of
# 0248c8f (last session's review mend, compiled and CI-tested only): every CUDA test program and
# gpu_bench built with -lineinfo (no change to the code generated); ctest -L cuda and the
# script's sanitizer pass; gpu_bench on the UNC scenes and the 90k, 250k and 1M cloths, two
# rounds; then ncu's full set, with per-instruction (SASS) counters and stall samples, for one
# launch each of the warp scan and the cells' pairs of the cloth ball's self query, exported as
# the source page (SASS, and CUDA lines) for the instruction-level account of the two kernels.
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
grep -h "ERROR SUMMARY" /tmp/chk/sanitizer-*.log >> $T 2>/dev/null
tail -30 /tmp/chk/check.log >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
for r in 1 2; do
  timeout 100 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 \
    --only unc --only cloth-90k --only cloth-250k --only cloth-1000k \
    --csv /tmp/chk/bench-$r.csv >> /tmp/chk/bench.log 2>&1
  echo "bench round $r rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/chk/bench-1.csv | sed 's/^/round,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/chk/bench-$r.csv | sed "s/^/$r,/" >> $OUT/bench.csv
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
$NCU --version >> $T 2>&1
for K in selfCandidatesWarpKernel selfCellPairsKernel; do
  timeout 150 $NCU --set full --import-source yes -k regex:$K -s 10 -c 1 -o /tmp/chk/$K \
    build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 1 --only unc-cloth-ball-self \
    > /tmp/chk/ncu-$K.log 2>&1
  echo "ncu $K rc=$?" >> $T
  $NCU -i /tmp/chk/$K.ncu-rep --page source --csv --print-source sass > /tmp/chk/$K-sass.csv 2>&1
  echo "sass export rc=$?" >> $T
  $NCU -i /tmp/chk/$K.ncu-rep --page source --csv --print-source cuda > /tmp/chk/$K-cuda.csv 2>&1
  echo "cuda export rc=$?" >> $T
  $NCU -i /tmp/chk/$K.ncu-rep --page details >> /tmp/chk/details.txt 2>&1
done
tar czf $OUT/source.tgz -C /tmp/chk selfCandidatesWarpKernel-sass.csv selfCandidatesWarpKernel-cuda.csv \
  selfCellPairsKernel-sass.csv selfCellPairsKernel-cuda.csv details.txt ncu-selfCandidatesWarpKernel.log \
  ncu-selfCellPairsKernel.log
tar czf $OUT/logs.tgz -C /tmp/chk check.log ctest.log bench.log $(cd /tmp/chk && ls sanitizer-*.log 2>/dev/null)
date >> $T
