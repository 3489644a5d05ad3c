#!/bin/bash
# Device call 6 (carry .fcl-debs and .gpu-data; 600 s): the topology version (a deformed mesh's
# re-hash compares no triangles on the host) and updateVertices in several threads. Builds the
# tree and a mutant (the topology shortcut off) in parallel; test_cuda_query (all) and
# test_hierarchy's HashedMesh tests; the mutant's new test; double_probe.cpp against the new
# library; kdet_bench part 2 (fracture, n-body, chair, adversarial, rigid scenes).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c6
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
CFG="-DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc -DCMAKE_EXE_LINKER_FLAGS=-L$L"
rm -rf /tmp/mut && mkdir -p /tmp/mut && cp -r CMakeLists.txt README.md cmake cuda docs include src tests benchmarks examples fuzz scripts /tmp/mut/ 2>/dev/null
sed -i 's/(m.topology == hm.topologyVersion() \&\& m.topology2 == t2 \&\& m.nt == src.nt())/false/' /tmp/mut/cuda/cuda_backend.cu
grep -c "m.topology == hm.topologyVersion()" /tmp/mut/cuda/cuda_backend.cu > $W/mutant-check.txt
(cmake -S . -B build-gpu $CFG "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" > $W/build.log 2>&1 &&
  cmake --build build-gpu --parallel 10 --target kdet_fcl test_cuda_query test_hierarchy kdet_bench >> $W/build.log 2>&1; echo $? > $W/build.rc) &
(cmake -S /tmp/mut -B /tmp/mut/b $CFG "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" > $W/mbuild.log 2>&1 &&
  cmake --build /tmp/mut/b --parallel 6 --target test_cuda_query >> $W/mbuild.log 2>&1; echo $? > $W/mbuild.rc) &
wait
echo "build rc=$(cat $W/build.rc) mutant build rc=$(cat $W/mbuild.rc) (mutant lines left: $(cat $W/mutant-check.txt))" >> $T
date >> $T
timeout 200 build-gpu/tests/test_cuda_query > $W/query.log 2>&1
echo "test_cuda_query rc=$?: $(grep -E 'PASSED|FAILED' $W/query.log | tr '\n' ' ')" >> $T
timeout 60 build-gpu/tests/test_hierarchy --gtest_filter='HashedMesh.*' > $W/hier.log 2>&1
echo "test_hierarchy HashedMesh rc=$?: $(grep -E 'PASSED|FAILED' $W/hier.log | tr '\n' ' ')" >> $T
timeout 60 /tmp/mut/b/tests/test_cuda_query --gtest_filter='*DeformedMeshesKeep*:*DeformationAndTopology*' > $W/mutant.log 2>&1
echo "mutant rc=$? ($(grep -c 'Failure' $W/mutant.log) failures)" >> $T
date >> $T
g++ -O2 -std=c++17 -isystem $D/usr/include -isystem $D/usr/include/x86_64-linux-gnu \
  -I /usr/include/eigen3 -I include -I . -I benchmarks \
  benchmarks/results/gpu-h100-session37/double_probe.cpp benchmarks/bench_scenes.cpp \
  -L build-gpu -L $L -lkdet_fcl -o /tmp/dprobe > $W/probe-build.log 2>&1
echo "probe build rc=$?" >> $T
LD_LIBRARY_PATH=$L:$PWD/build-gpu timeout 120 /tmp/dprobe > $OUT/probe.txt 2> $W/probe.err
echo "probe rc=$?" >> $T
date >> $T
left=$((585 - ($(date +%s) - START)))
M='kdet_cpu_2t,kdet_gpu,gpu_bvh,fcl_obbrss$'
mkdir -p $W/part2
timeout $left build-gpu/benchmarks/kdet_bench --reps 3 --frames 5 --rep-budget 5 --include-1m \
  --no-kfree --no-plots --methods $M --only fracture,nbody,chair,chazelle,huge,coplanar,rigid \
  --out $W/part2 > $W/part2.log 2>&1
echo "part2 rc=$? ($left s allowed)" >> $T
tar czf $OUT/out.tgz -C $W .
date >> $T
