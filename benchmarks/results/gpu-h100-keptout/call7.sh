#!/bin/bash
# Device call 7 (carry .fcl-debs and .gpu-data): where the exact kernel's time goes on few
# undecided pairs. ncu's full set with per-instruction (SASS) counters for one launch of
# selfExactKernel on the funnel (498 undecided pairs, 423 exactly coplanar) and on the 90k cloth
# (about 2,600, most of them colliding pairs whose final orientations the filter cannot prove);
# the kernel's details page and sass_account.py's summary come back.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
mkdir -p /tmp/c7
OUT=/tmp/c7 CTEST_ALL=0 JOBS=16 TARGETS="gpu_bench" scripts/gpu_check.sh > /tmp/c7/check.log 2>&1
echo "build rc=$? (ctest of the unbuilt tests fails: only gpu_bench was built)" >> $T
date >> $T
export LD_LIBRARY_PATH=$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
A=benchmarks/results/gpu-h100-source/sass_account.py
for sc in unc-funnel-self cloth-90k; do
  timeout 150 $NCU --set full --import-source yes -k regex:selfExactKernel -s 6 -c 1 -o /tmp/c7/$sc \
    build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 1 --only $sc > /tmp/c7/ncu-$sc.log 2>&1
  echo "ncu $sc rc=$?" >> $T
  $NCU -i /tmp/c7/$sc.ncu-rep --page source --csv --print-source sass > /tmp/c7/$sc-sass.csv 2>&1
  $NCU -i /tmp/c7/$sc.ncu-rep --page details > /tmp/c7/$sc-details.txt 2>&1
  echo "== $sc" >> $OUT/exact-account.txt
  python3 $A /tmp/c7/$sc-sass.csv --top 25 >> $OUT/exact-account.txt 2>&1
  cp /tmp/c7/$sc-details.txt $OUT/
done
tar czf $OUT/source.tgz -C /tmp/c7 $(cd /tmp/c7 && ls *-sass.csv ncu-*.log check.log 2>/dev/null)
date >> $T
