#!/bin/bash
# Device call 6 (carry .fcl-debs and .gpu-data; 600 s): the final tree (the pairs' order in the same
# trip as the counts, KDET_FCL_CUDA_ONE_TRIP), as a full gpu_bench run
# with every peer in one process: kDet GPU, the LBVH, kDet CPU on 2 and 16 threads and FCL
# (OBBRSS; refit + exhaustive collide per frame), on every scene including the 10M cloth
# (--big), 10 repeats; as gpu-h100-source/call5.sh. Builds the CUDA test programs and gpu_bench
# through scripts/gpu_check.sh, runs ctest -L cuda, then the bench (its log, CSV, JSON and
# Markdown table come back).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/ot6
OUT=/tmp/ot6 CTEST_ALL=0 JOBS=16 GPU_BENCH=1 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  GPU_BENCH_ARGS="--big --repeats 10 --json /tmp/ot6/gpu_bench.json --md /tmp/ot6/gpu_bench.md" \
  timeout 570 scripts/gpu_check.sh > /tmp/ot6/gpu_check.log 2>&1
echo "gpu_check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/ot6/ctest.log | head -30 >> $T
date >> $T
for f in gpu_check.log ctest.log nvidia-smi.txt gpu_bench.log gpu_bench.csv gpu_bench.json gpu_bench.md; do
  cp /tmp/ot6/$f $OUT/ 2>/dev/null || echo "missing $f" >> $T
done
