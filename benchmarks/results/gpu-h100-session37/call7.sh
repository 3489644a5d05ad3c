#!/bin/bash
# Device calls 7 and 8 (carry .fcl-debs and .gpu-data; 600 s each, the second on the warm
# machine): kdet_bench with the GPU methods' objects kept from run to run, the tree with the
# topology version and updateVertices in threads. PART=2 (call 7): builds kdet_bench and gpu_bench,
# runs the fracture, n-body, chair, adversarial and rigid scenes, then gpu_bench GPU only on the
# two cloth-ball scenes (the headline path, for no change); PART=1 (call 8): the UNC and cloth
# scenes with the build already there.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c7-$PART
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
if [ "$PART" = 2 ]; then
  cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
    -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
    -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
    "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
    -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
  cmake --build build-gpu --parallel 16 --target kdet_bench gpu_bench >> $W/build.log 2>&1
  echo "build rc=$?" >> $T
  date >> $T
fi
(lscpu; nproc) > $W/cpu.txt 2>&1
M='kdet_cpu_2t,kdet_gpu,gpu_bvh,fcl_obbrss$'
ONLY=unc,cloth
[ "$PART" = 2 ] && ONLY=fracture,nbody,chair,chazelle,huge,coplanar,rigid
left=$((560 - ($(date +%s) - START)))
timeout $left build-gpu/benchmarks/kdet_bench --reps 3 --frames 5 --rep-budget 5 --include-1m \
  --no-kfree --no-plots --methods $M --only $ONLY --out $W/part$PART > $W/part$PART.log 2>&1
echo "part$PART rc=$? ($left s allowed)" >> $T
date >> $T
if [ "$PART" = 2 ]; then
  left=$((570 - ($(date +%s) - START)))
  [ $left -gt 40 ] && timeout $left build-gpu/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 \
    --only unc-cloth-ball --csv $W/gpu_bench.csv > $W/gpu_bench.log 2>&1
  echo "gpu_bench rc=$?" >> $T
fi
tar czf $OUT/out.tgz -C $W .
date >> $T
