#!/bin/bash
# Device call 4 (carry .fcl-debs and .gpu-data; 600 s): the final tree (the plane filter's last
# step in closed form and queued per warp, KDET_FCL_CUDA_FILTER_QUEUE, default on). Builds the
# CUDA tests and gpu_bench and runs ctest -L cuda; beside that build, a mutant copy of the tree
# (the queued kernel without its final drain: the pairs left in a warp's queue are lost) whose
# filter test must fail; then compute-sanitizer memcheck and racecheck of the filter test.
set -u
cd "$(dirname "$0")/../../.."
R=$PWD
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c4
mkdir -p $W /tmp/mut
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
tar cf - --exclude=./build-gpu --exclude=./.git . | (cd /tmp/mut && tar xf -)
sed -i 's/^  if (lane < fill) finish(qk\[lane\], qs\[lane\]);$/  \/\/ (mutant: no drain)/' /tmp/mut/cuda/cuda_backend.cu
grep -c "(mutant: no drain)" /tmp/mut/cuda/cuda_backend.cu >> $T
(cd /tmp/mut && cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build-mut.log 2>&1 &&
  cmake --build build-gpu --parallel 5 --target test_cuda_query >> $W/build-mut.log 2>&1;
  echo "mutant build rc=$?" >> $T) &
OUT=$W CTEST_ALL=0 JOBS=11 \
  TARGETS="test_cuda_query test_cuda_upload test_cuda_box_test test_cuda_device test_cuda_bvh gpu_bench" \
  timeout 450 scripts/gpu_check.sh > $W/check.log 2>&1
echo "check rc=$?" >> $T
grep -E "tests passed|tests failed|Failed|\*\*\*" $W/ctest.log | head -30 >> $T
wait
date >> $T
export LD_LIBRARY_PATH=$L
F='CudaQuery.PlaneFilterOnOff*'
timeout 60 /tmp/mut/build-gpu/tests/test_cuda_query --gtest_filter="$F" > $W/tests-mut.log 2>&1
echo "mutant filter test rc=$? (must be non-zero)" >> $T
grep -E "^\[  (PASSED|FAILED) " $W/tests-mut.log >> $T; grep -c "Failure" $W/tests-mut.log >> $T
grep -m3 "queue 1" $W/tests-mut.log >> $T
SAN=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
for tool in memcheck racecheck; do
  left=$((585 - ($(date +%s) - START)))
  if [ $left -lt 20 ]; then echo "$tool skipped (time)" >> $T; continue; fi
  timeout $((left - 5)) $SAN --tool $tool --error-exitcode 3 build-gpu/tests/test_cuda_query \
    --gtest_filter="$F" > $W/$tool.log 2>&1
  echo "$tool rc=$?" >> $T; tail -2 $W/$tool.log >> $T
done
tar czf $OUT/logs.tgz -C $W $(cd $W && ls *.log)
date >> $T
