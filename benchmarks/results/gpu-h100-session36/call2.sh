#!/bin/bash
# Device call 2 (carry .fcl-debs and .gpu-data; 600 s): the candidates in 4 or 5 bytes only where
# 8-byte ones would take more than one round (KDET_FCL_CUDA_PACKED_CANDIDATES=1, the default; 2
# always, 0 never). test_cuda_query and test_cuda_upload whole; a mutant tree (the reader drops a
# 5-byte key's high byte; the default never packs) against the two new tests; compute-sanitizer
# memcheck of the new typed test (float); gpu_bench GPU only, three rounds of the knob at 1 and 0
# in turn; then the full run with every peer in one process (gpu_bench --big --repeats 10).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c2
mkdir -p $W /tmp/mut
tar cf - --exclude=./build-gpu . | tar xf - -C /tmp/mut
sed -i 's/      if (key_bytes == 5) key |= /      if (key_bytes == 6) key |= /' /tmp/mut/cuda/cuda_backend.cu
sed -i 's/      packing == 2 || (packing == 1 \&\& roundsFor/      packing == 2 || (packing == 3 \&\& roundsFor/' /tmp/mut/cuda/cuda_backend.cu
(cd /tmp/mut && diff -r /tmp/mut/cuda $OLDPWD/cuda > $W/mutant.diff; true)
grep -c "^[<>]" $W/mutant.diff >> $T
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
conf() {  # source dir, build dir, targets
  cmake -S $1 -B $2 -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
    -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
    -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
    "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
    -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/$(basename $2).log 2>&1
  cmake --build $2 --parallel 8 --target $3 >> $W/$(basename $2).log 2>&1
  echo "build $2 rc=$?" >> $T
}
conf . build-gpu "gpu_bench test_cuda_query test_cuda_upload" &
conf /tmp/mut /tmp/mut/build-mut "test_cuda_query" &
wait
date >> $T
t() {  # name, timeout, binary and args
  local name=$1 to=$2; shift 2
  timeout $to "$@" > $W/$name.log 2>&1
  echo "$name rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED|SKIPPED) |^\[  FAILED|^\[ memory" $W/$name.log | head -14 >> $T
}
t upload 120 build-gpu/tests/test_cuda_upload
t query-all 300 build-gpu/tests/test_cuda_query
t mut-query 120 /tmp/mut/build-mut/tests/test_cuda_query \
  --gtest_filter='*CandidatesInFour*:*TwoClothBallFramesAsOne*'
grep -c "Failure" $W/mut-query.log >> $T
grep -c "packing 1" $W/mut-query.log >> $T
grep -A3 "Failure" $W/mut-query.log | grep -c "candidate_key_bytes" >> $T
CS=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
t memcheck 150 $CS --tool memcheck --leak-check no --error-exitcode 3 \
  build-gpu/tests/test_cuda_query --gtest_filter='CudaQueryTyped/0.CandidatesInFour*'
grep -E "ERROR SUMMARY" $W/memcheck.log >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for round in 1 2 3; do
  for C in on off; do
    r=$((r + 1))
    case $C in on) E=(KDET_FCL_CUDA_PACKED_CANDIDATES=1);; off) E=(KDET_FCL_CUDA_PACKED_CANDIDATES=0);; esac
    timeout 60 env "${E[@]}" $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball \
      --only unc-n-body --only unc-funnel --only cloth-90k --only cloth-200k \
      --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r ($C) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,setting,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$C,/" >> $OUT/bench.csv
  done
done
grep "device memory" $W/bench.log | head -40 > $OUT/memory.txt
date >> $T
left=$((590 - ($(date +%s) - START)))
if [ $left -gt 200 ]; then
  timeout $left $B --big --repeats 10 --csv $OUT/gpu_bench.csv --json $OUT/gpu_bench.json \
    --md $OUT/gpu_bench.md > $W/gpu_bench.log 2>&1
  echo "full run rc=$?" >> $T
else
  echo "full run skipped (time: $left s)" >> $T
fi
cp $W/mutant.diff $OUT/
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log 2>/dev/null)
date >> $T
