#!/usr/bin/env bash
# The profile of the tree before (c7ccf85) in RESULTS-gpu.md (device call 1); the report was then printed with
#   ncu -i full.ncu-rep --print-details all   and   ncu -i full.ncu-rep --page source --csv --print-source sass
# Profile of phase 1 / filter / exact / output on the cloth ball and the two frames (ncu).
cd "$(dirname "$0")/.."
R=/tmp/p1; rm -rf $R; mkdir -p $R
finish() { tar -C $R -czf $OUT/p1.tgz . ; }
trap finish EXIT
date -u > $R/times.txt
OUT=$R/check TARGETS="gpu_bench" CTEST_ALL=0 JOBS=16 scripts/gpu_check.sh > $R/check.out 2>&1
echo "check rc=$?" >> $R/times.txt; date -u >> $R/times.txt
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
B=build-gpu/benchmarks/gpu_bench
NCU="ncu --clock-control none"
which ncu >> $R/times.txt 2>&1; ncu --version >> $R/times.txt 2>&1
# 1. per-kernel durations, every kernel of both scenes (kDet and LBVH)
for sc in unc-cloth-ball-self unc-cloth-ball-2frames; do
  timeout 150 $NCU --metrics gpu__time_duration.sum,launch__registers_per_thread,launch__grid_size,sm__warps_active.avg.pct_of_peak_sustained_active --csv --print-units base \
    $B --no-fcl --no-cpu --repeats 1 --only $sc > $R/dur-$sc.csv 2> $R/dur-$sc.err
  echo "dur $sc rc=$?" >> $R/times.txt; date -u >> $R/times.txt
done
# 2. full sections + source counters on the candidate, filter and exact kernels of the two frames
timeout 200 $NCU --set full --import-source no -k regex:"CandidatesWarp|planeFilter|ExactKernel" --launch-count 9 \
  -o $R/full $B --no-fcl --no-cpu --repeats 1 --only unc-cloth-ball-2frames > $R/full.log 2>&1
echo "full rc=$?" >> $R/times.txt; date -u >> $R/times.txt
$NCU -i $R/full.ncu-rep --print-details all > $R/full-details.txt 2>&1
$NCU -i $R/full.ncu-rep --page source --csv --print-source sass > $R/full-source.csv 2> $R/full-source.err
echo "source rc=$?" >> $R/times.txt; date -u >> $R/times.txt
ls -la $R >> $R/times.txt
cat $R/times.txt
