#!/bin/bash
# Device call 5 (carry .fcl-debs/root and .gpu-data): kdet_bench's GPU table on the tree with the
# scan's grouped cells (groups.diff): issue 5's ratios to the LBVH, in the same process, on the
# UNC and cloth scenes, the 1M cloth included, as session 43's call 3 ran it.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
ab_configure /tmp/s45c5
ab_targets kdet_bench
ab_table
tar czf $OUT/bench.tgz -C $W bench bench.log
date >> $T
