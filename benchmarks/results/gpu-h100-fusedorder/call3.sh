#!/bin/bash
# Device call 3 (carry .fcl-debs and .gpu-data; 600 s): the tree of call 1 (the counting order in
# one cooperative launch, KDET_FCL_CUDA_FUSED_ORDER default 2) as a full gpu_bench run with every
# peer in one process (kDet GPU, the LBVH, kDet CPU on 2 and 16 threads, FCL OBBRSS), every scene
# including the 10M cloth (--big), 10 repeats, as gpu-h100-onetrip/call6.sh; ctest -L cuda first.
# Then, in the time left, ncu's kernel durations (clocks unlocked) of the 20k cloth and the cloth
# ball with the fused order and with its five launches (KDET_FCL_CUDA_FUSED_ORDER=0), summed per
# frame by gpu-h100-profile/kernels_per_frame.py.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/c3
OUT=/tmp/c3 CTEST_ALL=0 JOBS=16 GPU_BENCH=1 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  GPU_BENCH_ARGS="--big --repeats 10 --json /tmp/c3/gpu_bench.json --md /tmp/c3/gpu_bench.md" \
  timeout 540 scripts/gpu_check.sh > /tmp/c3/gpu_check.log 2>&1
echo "gpu_check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" /tmp/c3/ctest.log | head -30 >> $T
date >> $T
for f in gpu_bench.csv gpu_bench.json gpu_bench.md; do
  cp /tmp/c3/$f $OUT/ 2>/dev/null || echo "missing $f" >> $T
done
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
B=build-gpu/benchmarks/gpu_bench
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in cloth-20k unc-cloth-ball-self; do
  for F in 2 0; do
    left=$((575 - ($(date +%s) - START)))
    if [ $left -lt 25 ]; then echo "ncu $sc $F skipped (time)" >> $T; continue; fi
    KDET_FCL_CUDA_FUSED_ORDER=$F timeout $((left - 5)) $NCU --clock-control none \
      --metrics gpu__time_duration.sum,launch__grid_size,launch__registers_per_thread \
      --csv --print-units base $B --no-fcl --no-cpu --repeats 3 --only $sc > /tmp/c3/dur-$sc-$F.csv 2> /tmp/c3/dur-$sc-$F.err
    echo "ncu $sc fused $F rc=$?" >> $T
    echo "== $sc, KDET_FCL_CUDA_FUSED_ORDER=$F" >> $OUT/kernels.txt
    python3 benchmarks/results/gpu-h100-profile/kernels_per_frame.py /tmp/c3/dur-$sc-$F.csv >> $OUT/kernels.txt 2>&1
  done
done
tar czf $OUT/logs.tgz -C /tmp/c3 gpu_check.log ctest.log gpu_bench.log nvidia-smi.txt \
  $(cd /tmp/c3 && ls dur-*.err 2>/dev/null)
date >> $T
