#!/bin/bash
# Device call 5 of session 46 (carry .fcl-debs/root and .gpu-data): kdet_bench's GPU table
# (unc,cloth, as call 3) on the tree as committed, whose kdet_bench now also compares every timed
# run's pair counts with its checking run's (*** UNSTEADY ***).
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_configure /tmp/s46c5
ab_targets kdet_bench
ab_table
cp $W/bench/bench.md $OUT/bench.md
gzip -c $W/bench.log > $OUT/bench.log.gz
date >> $T
