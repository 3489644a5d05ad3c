#!/bin/bash
# Where the candidate kernels' warps stall (carry .fcl-debs and .gpu-data; 600 s): builds
# gpu_bench (tree of main at 681d573), then ncu's occupancy, scheduler, warp-state, compute and
# memory sections for four launches each of the warp scan and the cells' pairs of the cloth
# ball's self query (text report), and the same for the 1M cloth (two launches each).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/chk
OUT=/tmp/chk CTEST_ALL=0 JOBS=16 TARGETS="gpu_bench" scripts/gpu_check.sh > /tmp/chk/check.log 2>&1
echo "check rc=$?" >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
SECTIONS="--section Occupancy --section SchedulerStats --section WarpStateStats --section ComputeWorkloadAnalysis --section MemoryWorkloadAnalysis --section LaunchStats"
timeout 200 $NCU $SECTIONS -k regex:"selfCandidatesWarpKernel|selfCellPairsKernel" -s 20 -c 4 \
  build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 1 --only unc-cloth-ball-self \
  > $OUT/ncu-cloth-ball.txt 2> $OUT/ncu-cloth-ball.err
echo "ncu cloth ball rc=$?" >> $T
date >> $T
timeout 200 $NCU $SECTIONS -k regex:"selfCandidatesWarpKernel|selfCellPairsKernel" -s 10 -c 2 \
  build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 1 --only cloth-1000k \
  > $OUT/ncu-cloth-1m.txt 2> $OUT/ncu-cloth-1m.err
echo "ncu 1M rc=$?" >> $T
date >> $T
