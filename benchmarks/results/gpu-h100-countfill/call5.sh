#!/bin/bash
# Fifth device call (branch device-pairs, the last ~270 s of device time; carry .fcl-debs and
# .gpu-data): call 4's pairs-on-device frames like with like. With KDET_FCL_CUDA_SELF_CACHE=0 the
# host queries keep no self result either, so the rigid sphere's self query runs on the device in
# both forms. gpu_bench only; its CSV straight to $OUT.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 TARGETS="gpu_bench" scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
KDET_FCL_CUDA_SELF_CACHE=0 timeout 60 build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 10 --only unc-cloth-ball-self \
  --only cloth-90k --only cloth-1000k --csv $OUT/nocache.csv > $OUT/nocache.log 2>&1
echo "bench rc=$?" >> $T
date >> $T
