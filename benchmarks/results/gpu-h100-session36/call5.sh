#!/bin/bash
# Device call 5 (carry .fcl-debs and .gpu-data; 600 s): a pooled read-back copies each chunk in
# as many pieces as threads (KDET_FCL_CUDA_DOWNLOAD_SPLIT, default 1). test_cuda_upload whole and
# test_cuda_query's read-back tests; a mutant tree (each piece one element short) against the
# staging test; gpu_bench GPU only on the cloth-ball scenes, three rounds of: split (default),
# whole chunks (SPLIT=0), split with 1 MiB chunks; the two cloth-ball scenes in twelve
# processes; then, if time is left, the full run with every peer in one process.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c5
mkdir -p $W /tmp/mut
tar cf - --exclude=./build-gpu . | tar xf - -C /tmp/mut
sed -i 's/      const std::size_t from = std::min(len, q \* piece), to = std::min(len, from + piece);/      const std::size_t from = std::min(len, q * piece), to = std::min(len, from + piece - 1);/' /tmp/mut/cuda/staged_upload.h
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
conf /tmp/mut /tmp/mut/build-mut "test_cuda_upload" &
wait
date >> $T
t() {  # name, timeout, binary and args
  local name=$1 to=$2; shift 2
  timeout $to "$@" > $W/$name.log 2>&1
  echo "$name rc=$?" >> $T
  grep -E "^\[  (PASSED|FAILED|SKIPPED) |^\[  FAILED" $W/$name.log | head -14 >> $T
}
t upload 120 build-gpu/tests/test_cuda_upload
t query-readback 150 build-gpu/tests/test_cuda_query \
  --gtest_filter='*ResultsKept*:*Forecast*:*OneTrip*:*Knob*:*Unc*:*TwoClothBall*'
t mut-upload 120 /tmp/mut/build-mut/tests/test_cuda_upload --gtest_filter='PooledDownload.*'
date >> $T
B=build-gpu/benchmarks/gpu_bench
r=0
for round in 1 2 3; do
  for C in split whole split1m; do
    r=$((r + 1))
    case $C in
      split) E=(KDET_FCL_CUDA_DOWNLOAD_SPLIT=1);;
      whole) E=(KDET_FCL_CUDA_DOWNLOAD_SPLIT=0);;
      split1m) E=(KDET_FCL_CUDA_DOWNLOAD_SPLIT=1 KDET_FCL_CUDA_DOWNLOAD_CHUNK=1048576);;
    esac
    timeout 60 env "${E[@]}" $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball \
      --only unc-n-body-2 --csv $W/bench-$r.csv >> $W/bench.log 2>&1
    echo "bench $r ($C) rc=$?" >> $T
    if [ $r = 1 ]; then head -1 $W/bench-1.csv | sed 's/^/round,setting,/' > $OUT/bench.csv; fi
    tail -n +2 $W/bench-$r.csv | sed "s/^/$round,$C,/" >> $OUT/bench.csv
  done
done
date >> $T
for r in $(seq 1 12); do
  left=$((400 - ($(date +%s) - START)))
  if [ $left -lt 10 ]; then echo "process $r skipped (time)" >> $T; break; fi
  timeout $left $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball --csv $W/p-$r.csv >> $W/twelve.log 2>&1
  echo "process $r rc=$?" >> $T
  if [ $r = 1 ]; then head -1 $W/p-1.csv | sed 's/^/process,/' > $OUT/twelve.csv; fi
  tail -n +2 $W/p-$r.csv | sed "s/^/$r,/" >> $OUT/twelve.csv
done
date >> $T
left=$((590 - ($(date +%s) - START)))
if [ $left -gt 170 ]; then
  timeout $left $B --big --repeats 10 --csv $OUT/gpu_bench.csv --json $OUT/gpu_bench.json \
    --md $OUT/gpu_bench.md > $W/gpu_bench.log 2>&1
  echo "full run rc=$?" >> $T
else
  echo "full run skipped (time: $left s)" >> $T
fi
cp $W/mutant.diff $OUT/
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log 2>/dev/null)
date >> $T
