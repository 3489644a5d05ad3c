#!/bin/bash
# Device call 9 (carry .fcl-debs and .gpu-data; 600 s): the counting order's segments at 17 bits
# by default (KDET_FCL_CUDA_COUNT_ORDER_BITS). Every CTest entry of test_cuda_query (the new
# test_cuda_query_order_bits among them: the order's test at 12 bits); gpu_bench GPU only on the
# cloth-ball and n-body scenes and the 1M cloth, three rounds of 17 (the default) and 16 bits.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c9
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target gpu_bench test_cuda_query >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
timeout 300 ctest --test-dir build-gpu -R test_cuda_query -V > $W/ctest.log 2>&1
echo "ctest rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*|Test +#" $W/ctest.log | head -20 >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for round in 1 2 3; do
  for C in 17 16; do
    r=$((r + 1))
    timeout 60 env KDET_FCL_CUDA_COUNT_ORDER_BITS=$C $B --no-fcl --no-cpu --repeats 20 \
      --only unc-cloth-ball --only unc-n-body --only cloth-1000k --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r ($C) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,setting,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$C,/" >> $OUT/bench.csv
  done
done
grep "device memory" $W/bench.log | cut -c1-100 > $OUT/memory.txt
gzip -c $W/ctest.log > $OUT/ctest.log.gz
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log 2>/dev/null)
date >> $T
