#!/bin/bash
# Session 51, call 2 (fresh machine; carry .fcl-debs/root and .gpu-data): the kdet tool's
# --backend cpu|cuda|auto and `kdet info`, and kdet_fcl::cudaDeviceBytesInUse() (new), on a GPU.
#   1. the library, kdet, test_backend, test_cuda_device and test_cuda_query;
#   2. ctest's cli tests (cli_backend takes its GPU branch here: the GPU's pairs against the
#      CPU's, the device memory reported), test_backend, test_cuda_device, all of test_cuda_query;
#   3. what a user sees: kdet info; kdet self on the cloth ball, CPU then GPU; kdet demo on the
#      GPU over 5 frames (about 100k triangles), float and double.
# Outputs: $OUT/times.txt, $OUT/cli.txt (step 3), $OUT/out.tgz (the logs).
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
W=/tmp/s51b
ab_configure $W
ab_targets kdet_fcl kdet test_backend test_cuda_device test_cuda_query
(cd build-gpu && ctest -L cli --output-on-failure) > $W/ctest-cli.txt 2>&1
echo "ctest -L cli rc=$? $(date +%T)" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest-cli.txt >> $T
(cd build-gpu && ctest -R cli_backend -V) > $W/ctest-cli-backend-v.txt 2>&1
grep -E "kdet info|CUDA |device [0-9]|demo pair counts" $W/ctest-cli-backend-v.txt >> $T
build-gpu/tests/test_backend > $W/test-backend.txt 2>&1
echo "test_backend rc=$? $(date +%T)" >> $T
build-gpu/tests/test_cuda_device > $W/test-device.txt 2>&1
echo "test_cuda_device rc=$? $(date +%T)" >> $T
ab_gtest all '*'
grep -E "Failure|Which is|Expected|actual" $W/test-all.txt | head -40 >> $T
C=$OUT/cli.txt
K=build-gpu/kdet
BALL=$KDET_FCL_DATA_DIR/unc/cloth-ball/cloth_ball92.ply
{ echo "== kdet info"; $K info
  echo "== kdet self cloth_ball92.ply --backend cpu"; $K self $BALL --backend cpu
  echo "== kdet self cloth_ball92.ply --backend cuda"; $K self $BALL --backend cuda
  echo "== kdet self cloth_ball92.ply --backend auto --float"; $K self $BALL --backend auto --float
  echo "== kdet demo --backend cuda --frames 5 --float"; $K demo --backend cuda --frames 5 --float
  echo "== kdet demo --backend cuda --frames 5"; $K demo --backend cuda --frames 5
  echo "== kdet demo --frames 5 (cpu)"; $K demo --frames 5
} > $C 2>&1
echo "cli runs rc=$? $(date +%T)" >> $T
date >> $T
tar czf $OUT/out.tgz -C $W .
