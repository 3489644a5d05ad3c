#!/bin/bash
# Device call 5 (carry .fcl-debs and .gpu-data; 600 s): the exact kernels' groups of 32 pairs
# handed to warps of different blocks (KDET_FCL_CUDA_EXACT_SPREAD, default 1; call 3's spread of
# single pairs over every warp was taken back). Builds test_cuda_query and gpu_bench (cmake as
# scripts/gpu_check.sh); runs the coplanar-pairs and knob tests; gpu_bench (GPU only) in four
# rounds alternating the knob (1, 0); ncu's durations of the exact kernels of the cloth ball and
# the 200k cloth with the knob at 1 and 0; then the full gpu_bench run with every peer in one
# process (--big --repeats 10), with the knob at the A/B's winner (the sum of the scenes' median
# frames; recorded in times.txt).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c5
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_query gpu_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
timeout 60 build-gpu/tests/test_cuda_query \
  --gtest_filter='CudaQuery.CoplanarPairs*:CudaQuery.EveryKnob*:CudaQuery.PlaneFilterOnOff*' \
  > $W/tests.log 2>&1
echo "tests rc=$?" >> $T; grep -E "^\[  (PASSED|FAILED) " $W/tests.log >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for R in 1 0 1 0; do
  r=$((r + 1))
  KDET_FCL_CUDA_EXACT_SPREAD=$R timeout 40 $B --no-fcl --no-cpu --repeats 20 \
    --only unc-cloth-ball --only unc-n-body --only cloth-200k --only cloth-1000k \
    --csv $W/bench-$r.csv >> $W/bench.log 2>&1
  echo "bench round $r (exact spread $R) rc=$?" >> $T
  if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,spread,/' > $OUT/bench.csv; fi
  tail -n +2 $W/bench-$r.csv | sed "s/^/$r,$R,/" >> $OUT/bench.csv
done
WIN=$(python3 - $OUT/bench.csv <<'PY'
import csv, sys, statistics, collections
d = collections.defaultdict(lambda: collections.defaultdict(list))
for r in csv.DictReader(open(sys.argv[1])):
    d[r['spread']][r['scene']].append(float(r['kdet_gpu_ms']))
tot = {k: sum(statistics.median(v) for v in s.values()) for k, s in d.items()}
print('1' if tot.get('1', 9e9) <= tot.get('0', 9e9) else '0')
PY
)
echo "winner: KDET_FCL_CUDA_EXACT_SPREAD=$WIN" >> $T
date >> $T
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
for sc in unc-cloth-ball-self cloth-200k; do
  for R in 1 0; do
    KDET_FCL_CUDA_EXACT_SPREAD=$R timeout 40 $NCU --clock-control none --kernel-name regex:"Exact" \
      --metrics gpu__time_duration.sum,launch__grid_size --csv --print-units base \
      $B --no-fcl --no-cpu --repeats 2 --only $sc > $W/exact-$sc-$R.csv 2> $W/exact-$sc-$R.err
    echo "ncu $sc spread $R rc=$?" >> $T
    gzip -c $W/exact-$sc-$R.csv > $OUT/exact-$sc-$R.csv.gz
  done
done
date >> $T
left=$((590 - ($(date +%s) - START)))
KDET_FCL_CUDA_EXACT_SPREAD=$WIN timeout $left $B --big --repeats 10 --csv $OUT/gpu_bench.csv \
  --json $OUT/gpu_bench.json --md $OUT/gpu_bench.md > $W/gpu_bench.log 2>&1
echo "full run (spread $WIN) rc=$?" >> $T
tar czf $OUT/logs.tgz -C $W build.log tests.log bench.log gpu_bench.log $(cd $W && ls *.err 2>/dev/null)
date >> $T
