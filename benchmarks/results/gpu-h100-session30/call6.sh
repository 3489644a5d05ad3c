#!/bin/bash
# Device call 6 (carry .fcl-debs and .gpu-data; 600 s): mutation check of the one trip's copy
# limit. Builds test_cuda_query with copy_most back at one chunk whatever
# KDET_FCL_CUDA_ONE_TRIP_COPY says (the code before), runs the one-trip test, which must fail;
# then the tree restored, rebuilt, and the same test, which must pass.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c6
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cp cuda/cuda_backend.cu $W/cuda_backend.cu.orig
sed -i 's/std::min<std::size_t>(oneTripCopyChunks() \* chunk_pairs, 0x7FFFFFFF));/std::min<std::size_t>(chunk_pairs, 0x7FFFFFFF));/' cuda/cuda_backend.cu
grep -c "std::min<std::size_t>(chunk_pairs, 0x7FFFFFFF));" cuda/cuda_backend.cu >> $T
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target test_cuda_query >> $W/build.log 2>&1
echo "mutant build rc=$?" >> $T
F='*OneTripBringsSmallHostResults*'
timeout 60 build-gpu/tests/test_cuda_query --gtest_filter="$F" > $W/tests-mut.log 2>&1
echo "mutant tests rc=$? (must be non-zero)" >> $T
grep -E "^\[  (PASSED|FAILED) " $W/tests-mut.log >> $T; grep -c "Failure" $W/tests-mut.log >> $T
cp $W/cuda_backend.cu.orig cuda/cuda_backend.cu
cmake --build build-gpu --parallel 16 --target test_cuda_query > $W/build-restored.log 2>&1
echo "restored build rc=$?" >> $T
timeout 60 build-gpu/tests/test_cuda_query --gtest_filter="$F" > $W/tests.log 2>&1
echo "tests rc=$?" >> $T
grep -E "^\[  (PASSED|FAILED) " $W/tests.log >> $T
tar czf $OUT/logs.tgz -C $W build.log tests-mut.log build-restored.log tests.log
date >> $T
