#!/bin/bash
# Device call 5 (carry .fcl-debs and .gpu-data; 600 s): the final tree (the counting order in
# one cooperative launch, KDET_FCL_CUDA_FUSED_ORDER default 2) as a full gpu_bench run with every
# peer in one process (kDet GPU, the LBVH, kDet CPU on 2 and 16 threads, FCL OBBRSS), every scene
# including the 10M cloth (--big), 10 repeats, as gpu-h100-onetrip/call6.sh; ctest -L cuda first.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/c5
OUT=/tmp/c5 CTEST_ALL=0 JOBS=16 GPU_BENCH=1 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  GPU_BENCH_ARGS="--big --repeats 10 --json /tmp/c5/gpu_bench.json --md /tmp/c5/gpu_bench.md" \
  timeout 540 scripts/gpu_check.sh > /tmp/c5/gpu_check.log 2>&1
echo "gpu_check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/c5/ctest.log | head -30 >> $T
date >> $T
for f in gpu_bench.csv gpu_bench.json gpu_bench.md; do
  cp /tmp/c5/$f $OUT/ 2>/dev/null || echo "missing $f" >> $T
done
tar czf $OUT/logs.tgz -C /tmp/c5 gpu_check.log ctest.log gpu_bench.log nvidia-smi.txt
date >> $T
