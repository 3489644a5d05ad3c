#!/bin/bash
# Device call 3 (carry .fcl-debs and .gpu-data; 600 s): the forecast's read-back with its floor
# of one read-back chunk. test_cuda_upload and test_cuda_query whole; compute-sanitizer memcheck
# of the new tests; gpu_bench GPU only, three rounds of KDET_FCL_CUDA_ONE_TRIP_FORECAST at 1 and 0
# in turn; and a mutant tree (/tmp/mut): the forecast never recorded (runQuery) and the staged
# download consuming every chunk queued ahead instead of those of its count (staged_upload.h),
# against the two new tests.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c3
mkdir -p $W /tmp/mut
tar cf - --exclude=./build-gpu . | tar xf - -C /tmp/mut
sed -i 's/    if (forecast != nullptr) \*forecast = m;/    (void)forecast;/' /tmp/mut/cuda/cuda_backend.cu
sed -i 's/  const std::size_t chunks = (count + events->chunk - 1) \/ events->chunk;/  const std::size_t chunks = events->ev.size();/' /tmp/mut/cuda/staged_upload.h
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
conf /tmp/mut /tmp/mut/build-mut "test_cuda_query test_cuda_upload" &
wait
date >> $T
t() {  # name, timeout, binary and args
  local name=$1 to=$2; shift 2
  timeout $to "$@" > $W/$name.log 2>&1
  echo "$name rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED|SKIPPED) |^\[  FAILED" $W/$name.log | head -12 >> $T
}
t upload 120 build-gpu/tests/test_cuda_upload
t query-all 200 build-gpu/tests/test_cuda_query
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for round in 1 2 3; do
  for C in on off; do
    r=$((r + 1))
    case $C in on) E=(KDET_FCL_CUDA_ONE_TRIP_FORECAST=1);; off) E=(KDET_FCL_CUDA_ONE_TRIP_FORECAST=0);; esac
    timeout 60 env "${E[@]}" $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball \
      --only unc-n-body --only unc-funnel --only cloth-20k --only cloth-90k --only cloth-1000k \
      --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r ($C) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,setting,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$C,/" >> $OUT/bench.csv
  done
done
date >> $T
t mut-upload 120 /tmp/mut/build-mut/tests/test_cuda_upload --gtest_filter='*Ahead*'
t mut-query 120 /tmp/mut/build-mut/tests/test_cuda_query --gtest_filter='*Forecast*'
CS=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
left=$((585 - ($(date +%s) - START)))
if [ $left -gt 40 ]; then
  t memcheck $((left - 20)) $CS --tool memcheck --leak-check no --error-exitcode 3 \
    build-gpu/tests/test_cuda_query --gtest_filter='CudaQueryTyped/0.Forecast*'
  grep -E "ERROR SUMMARY" $W/memcheck.log >> $T
fi
left=$((585 - ($(date +%s) - START)))
if [ $left -gt 30 ]; then
  t memcheck-upload $((left - 10)) $CS --tool memcheck --leak-check no --error-exitcode 3 \
    build-gpu/tests/test_cuda_upload --gtest_filter='*Ahead*'
  grep -E "ERROR SUMMARY" $W/memcheck-upload.log >> $T
fi
cp $W/mutant.diff $OUT/
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log 2>/dev/null)
date >> $T
