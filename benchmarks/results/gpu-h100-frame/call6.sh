#!/bin/bash
# Sixth device call (carry .fcl-debs and .gpu-data): the tree of call 5 with the exact zero of
# points equal in one coordinate taken before any expansion (sameCoordinate in orient3dSign,
# the same test in orient2dSign): every one of the cloth ball's 976 undecided pairs has its
# exact zeros from an axis-aligned plane (CPU count). Builds every CUDA test program and
# gpu_bench; ctest -L cuda and the sanitizer pass; gpu_bench as call 2 (the filter deciding
# or not, in turn); ncu's kernel durations of the two cloth-ball frames and the cloth ball.
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
grep -h "\[ filter   \]" /tmp/chk/ctest.log | head -4 >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
B=build-gpu/benchmarks/gpu_bench
r=0
for C in 1 0 1 0; do
  r=$((r + 1))
  KDET_FCL_CUDA_FILTER_DECIDES=$C timeout 100 $B --no-fcl --no-cpu --repeats 20 \
    --only unc --only cloth-90k --only cloth-250k --only cloth-1000k \
    --csv /tmp/chk/bench-$r.csv >> /tmp/chk/bench.log 2>&1
  echo "bench round $r (decides $C) rc=$?" >> $T
  if [ $r = 1 ]; then head -1 /tmp/chk/bench-1.csv | sed 's/^/round,decides,/' > $OUT/bench.csv; fi
  tail -n +2 /tmp/chk/bench-$r.csv | sed "s/^/$r,$C,/" >> $OUT/bench.csv
done
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in unc-cloth-ball-2frames unc-cloth-ball-self; do
  timeout 100 $NCU --clock-control none --metrics gpu__time_duration.sum,launch__grid_size,launch__registers_per_thread \
    --csv --print-units base $B --no-fcl --no-cpu --repeats 3 --only $sc > /tmp/chk/dur-$sc.csv 2> /tmp/chk/dur-$sc.err
  echo "ncu $sc rc=$?" >> $T
  echo "== $sc" >> $OUT/kernels.txt
  python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py /tmp/chk/dur-$sc.csv >> $OUT/kernels.txt 2>&1
done
tar czf $OUT/logs.tgz -C /tmp/chk check.log ctest.log bench.log \
  $(cd /tmp/chk && ls sanitizer-*.log build.log dur-*.err 2>/dev/null)
date >> $T
