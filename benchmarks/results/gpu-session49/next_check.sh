#!/bin/bash
# Prepared in session 49 for the next device session; not run (carry .fcl-debs/root and
# .gpu-data). The final tree's GPU check in two calls on one machine, since the whole check no
# longer fits one call (session 49's call 4: the build took 4 minutes and racecheck was cut):
#   next_check.sh check   (fresh machine, about 7 minutes) scripts/gpu_check.sh with ctest -L cuda,
#                         memcheck alone and gpu_bench on the cloth ball: the first device run of
#                         ARehashGraphWhoseBuffersMovedIsCapturedAgain in its final form;
#   next_check.sh race    (the same machine, about 6 minutes; its build is reused) ctest -L cuda
#                         again and racecheck alone.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
TARGETS="test_cuda_device test_cuda_query test_cuda_bvh test_cuda_upload test_cuda_box_test test_cuda_warp_search test_cuda_predicates gpu_bench"
date > $T
case "${1:-}" in
  check)
    rm -rf build-gpu
    OUT=$OUT/check CTEST_ALL=0 SANITIZER=1 SANITIZER_TOOLS=memcheck GPU_BENCH=1 \
      GPU_BENCH_ARGS="--no-fcl --no-cpu --repeats 20 --only unc-cloth-ball" TARGETS="$TARGETS" \
      timeout 580 scripts/gpu_check.sh > $OUT/gpu_check.log 2>&1
    echo "gpu_check (memcheck) rc=$? $(date +%T)" >> $T ;;
  race)
    OUT=$OUT/race CTEST_ALL=0 SANITIZER=1 SANITIZER_TOOLS=racecheck TARGETS="$TARGETS" \
      timeout 580 scripts/gpu_check.sh > $OUT/gpu_check.log 2>&1
    echo "gpu_check (racecheck) rc=$? $(date +%T)" >> $T ;;
  *) echo "usage: next_check.sh check|race" >&2; exit 2 ;;
esac
gzip -f $OUT/*/ctest.log $OUT/*/build.log 2>/dev/null
date >> $T
