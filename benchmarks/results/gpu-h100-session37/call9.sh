#!/bin/bash
# Device call 9 (warm machine after call 8, build-gpu there; carry .fcl-debs/root and .gpu-data):
# kdet_bench part 2 (fracture, n-body, chair, adversarial, rigid scenes); then a mutant whose
# topology shortcut is off (every re-hash compares the triangles on the host, as before) builds
# gpu_bench, and the two gpu_bench builds run in turn, GPU only, on the cloth ball and the 1M cloth.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c9
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
M='kdet_cpu_2t,kdet_gpu,gpu_bvh,fcl_obbrss$'
timeout 260 build-gpu/benchmarks/kdet_bench --reps 3 --frames 5 --rep-budget 5 \
  --no-kfree --no-plots --methods $M --only fracture,nbody,chair,chazelle,huge,coplanar,rigid \
  --out $W/part2 > $W/part2.log 2>&1
echo "part2 rc=$?" >> $T
date >> $T
rm -rf /tmp/mut && mkdir -p /tmp/mut && cp -r CMakeLists.txt README.md cmake cuda docs include src tests benchmarks examples fuzz scripts /tmp/mut/ 2>/dev/null
sed -i 's/(m.topology == hm.topologyVersion() \&\& m.topology2 == t2 \&\& m.nt == src.nt())/false/' /tmp/mut/cuda/cuda_backend.cu
echo "mutant lines left: $(grep -c 'm.topology == hm.topologyVersion()' /tmp/mut/cuda/cuda_backend.cu)" >> $T
cmake -S /tmp/mut -B /tmp/mut/b -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/mbuild.log 2>&1
cmake --build /tmp/mut/b --parallel 16 --target gpu_bench >> $W/mbuild.log 2>&1
echo "mutant build rc=$?" >> $T
date >> $T
for round in 1 2 3; do
  for v in tree mutant; do
    left=$((560 - ($(date +%s) - START)))
    [ $left -lt 40 ] && { echo "round $round $v skipped (time)" >> $T; continue; }
    B=build-gpu/benchmarks/gpu_bench; [ $v = mutant ] && B=/tmp/mut/b/benchmarks/gpu_bench
    timeout $((left - 10)) $B --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball,cloth-1000k \
      --csv $W/ab-$v-$round.csv > $W/ab-$v-$round.log 2>&1
    echo "round $round $v rc=$?" >> $T
  done
done
tar czf $OUT/out.tgz -C $W .
date >> $T
