#!/bin/bash
# Prepared in session 45 (no device time left), run in session 46 (call 1). Device script
# (carry .fcl-debs/root and .gpu-data): does kdet_bench's unc-n-body-pair disagreement of call 5
# come from the cells' groups (groups.diff) or from the tree without them?
#   1. kdet_bench's GPU table of the UNC n-body scenes (the anim scene first, then the pair, as in
#      call 5, where the pair's meshes can take over the anim scene's cache entry) on the tree
#      as it is, three runs;
#   2. groups.diff applied to the device's copy, rebuilt, the same three runs with the groups (y)
#      and three with KDET_FCL_CUDA_CELL_GROUPS=0;
#   3. the whole table of call 5 (UNC and cloth scenes) once in each build.
# kdet_bench exits 1 on a disagreement; each run's table and log go to $OUT/runs.tgz.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_configure /tmp/next
bench() {  # bench NAME ONLY [ENV...]
  local name=$1 only=$2
  shift 2
  env "$@" timeout 150 build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 \
    --no-kfree --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only $only \
    --out $W/$name > $W/$name.log 2>&1
  echo "kdet_bench $name rc=$? $(date +%T)" >> $T
  grep -h "DISAGREEMENT" $W/$name.log >> $T
  mkdir -p $W/md
  cp $W/$name/bench.md $W/md/$name.md 2>/dev/null
  cp $W/$name.log $W/md/$name.log
  tar czf $OUT/runs.tgz -C $W md  # each run's table and log (at most 8 files come back)
}
cmake --build build-gpu --parallel 16 --target kdet_bench >> $W/build.log 2>&1
echo "build (tree) rc=$? $(date +%T)" >> $T
for r in 1 2 3; do bench tree-nbody-$r unc-n-body; done
bench tree-all unc,cloth
git apply benchmarks/results/gpu-session45/groups.diff >> $T 2>&1
echo "groups.diff applied rc=$? $(date +%T)" >> $T
cmake --build build-gpu --parallel 16 --target kdet_bench >> $W/build.log 2>&1
echo "build (groups) rc=$? $(date +%T)" >> $T
for r in 1 2 3; do
  bench groups-nbody-$r unc-n-body
  bench none-nbody-$r unc-n-body KDET_FCL_CUDA_CELL_GROUPS=0
done
bench groups-all unc,cloth
date >> $T
