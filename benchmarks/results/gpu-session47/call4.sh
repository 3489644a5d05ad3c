#!/bin/bash
# Device call 4 of session 47 (carry .fcl-debs/root and .gpu-data): kdet_bench's GPU table on
# the UNC cloth-ball scenes and the 90k cloth, five processes in a row (the LBVH in each), on the
# committed tree: is call 1's 3.29x for the cloth ball (one process) this machine's steady figure?
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_configure /tmp/s47c4
ab_targets kdet_bench
for r in 1 2 3 4 5; do
  timeout 60 build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree \
    --no-plots --methods 'kdet_gpu$,gpu_bvh$' --only unc-cloth-ball,cloth-90k --out $W/bench-$r \
    > $W/bench-$r.log 2>&1
  echo "kdet_bench $r rc=$? $(date +%T)" >> $T
  grep -h "DISAGREEMENT \*\*\*\|UNSTEADY" $W/bench-$r.log >> $T
  python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench-$r/bench.json \
    > $W/table-$r.md 2>&1
  grep -E "^\| (unc-cloth-ball|cloth-90k)" $W/table-$r.md | sed "s/^/$r /" >> $OUT/runs.md
done
cp $W/table-1.md $OUT/table-1.md
tar czf $OUT/logs.tgz -C $W --exclude='*.json' .
date >> $T
