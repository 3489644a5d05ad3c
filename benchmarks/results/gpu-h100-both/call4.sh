#!/bin/bash
# Fourth device call (the session's last 7 minutes of device time; carry .fcl-debs and .gpu-data):
# why countFillKernel takes ~308 us at 1M. Builds gpu_bench only, then one ncu report of the
# first counting build's countFillKernel on the 1M cloth (KDET_FCL_CUDA_COUNT_BUILD=1): speed of
# light, memory, scheduler and warp-state sections, and the source counters. Outputs straight in
# $OUT (no archive: a cut-off call still returns them).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 TARGETS="gpu_bench" scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$? (ctest -L cuda fails here: only gpu_bench is built)" >> $T
tail -3 /tmp/chk/build.log >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
KDET_FCL_CUDA_COUNT_BUILD=1 timeout 120 $NCU --clock-control none --kernel-name regex:countFillKernel -c 1 \
  --section SpeedOfLight --section MemoryWorkloadAnalysis --section SchedulerStats --section WarpStateStats \
  --section Occupancy --section LaunchStats --section SourceCounters --import-source no \
  -o $OUT/countfill -f build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 1 --only cloth-1000k \
  > $OUT/ncu.log 2>&1
echo "ncu rc=$?" >> $T
timeout 30 $NCU -i $OUT/countfill.ncu-rep --page details > $OUT/countfill-details.txt 2>&1
echo "details rc=$?" >> $T
date >> $T
