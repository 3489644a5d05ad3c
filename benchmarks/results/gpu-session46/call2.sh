#!/bin/bash
# Device call 2 of session 46 (carry .fcl-debs/root and .gpu-data), on the tree with groups.diff
# and debug.diff applied: which earlier scenes make kdet_bench's unc-n-body-pair disagree with the
# cells' groups on, and is the grouped layout right (KDET_DEBUG_GROUPS: debugGroupsKernel checks
# every grouped counting build, acquire() prints each cache entry's rebuild).
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_configure /tmp/s46c2
cmake --build build-gpu --parallel 16 --target kdet_bench >> $W/build.log 2>&1
echo "build rc=$? $(date +%T)" >> $T
bench() {  # bench NAME ONLY [ENV...]
  local name=$1 only=$2
  shift 2
  env KDET_DEBUG_GROUPS=1 "$@" timeout 100 build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 \
    --rep-budget 5 --no-kfree --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m \
    --only $only --out $W/$name > $W/$name.log 2>&1
  echo "kdet_bench $name $* rc=$? $(date +%T) DBGBAD=$(grep -c DBGBAD $W/$name.log) DBGBUILD=$(grep -c DBGBUILD $W/$name.log)" >> $T
  grep -h "DISAGREEMENT \*\*\*" $W/$name.log >> $T
  tar czf $OUT/logs.tgz -C $W --exclude=build.log $(cd $W && ls *.log)
}
bench unc unc
bench funnel-nbody unc-funnel,unc-n-body
bench ball-nbody unc-cloth-ball,unc-n-body
bench unc-nograph unc KDET_FCL_CUDA_REHASH_GRAPH=0
bench all unc,cloth
date >> $T
