#!/bin/bash
# Third device call of branch countfill-flag (carry .fcl-debs and .gpu-data): why the UNC cloth
# ball's two frames (one joint hash of 184k triangles) query slower after a counting build than
# after the sort (call 2: build -0.03 to -0.06 ms, frame +0.05 to +0.09 ms). ncu durations and
# L2 hit rates of every kDet kernel of that scene and of the cloth ball alone, with the count
# (KDET_FCL_CUDA_COUNT_BUILD=1) and with the sort (0). Writes $OUT/out.tgz and $OUT/times.txt.
set -u
cd "$(dirname "$0")/../../.."
FINAL=$OUT
OUT=$FINAL/w
mkdir -p $OUT
trap 'cp $OUT/times.txt $FINAL/times.txt; tar czf $FINAL/out.tgz -C $FINAL w && rm -rf $FINAL/w' EXIT
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
OUT=$OUT/check CTEST_ALL=0 JOBS=16 TARGETS="gpu_bench" scripts/gpu_check.sh > $OUT/check.log 2>&1
echo "check rc=$?" >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
date >> $T
B=build-gpu/benchmarks/gpu_bench
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in unc-cloth-ball-2frames unc-cloth-ball-self; do
  for v in 0 1; do
    KDET_FCL_CUDA_COUNT_BUILD=$v timeout 100 $NCU --clock-control none --kernel-name regex:'self|inter|plane|upper|count|scatter|fill|entries|heads|cells|triangles|grid|unpack|Radix|Scan' -c 800 \
      --metrics gpu__time_duration.sum,lts__t_sector_hit_rate.pct --csv $B --no-fcl --no-cpu --repeats 2 --only $sc > $OUT/ncu-$sc-$v.csv 2> $OUT/ncu-$sc-$v.err
    echo "ncu $sc count=$v rc=$?" >> $T
  done
done
date >> $T
