#!/bin/bash
# Device call 5 (carry .fcl-debs/root and .gpu-data; cold machine): the FCL entry points'
# deformation path (session 38: a deformed model's positions go through commitVertices, the
# triangles keep their topology version) timed on the CUDA backend, which session 38 left
# untimed. fcl_gpu_probe.cpp against the final library and against the same tree with that path
# off (every change a new mesh through setMesh, as before session 38: the mutant below), in
# alternating rounds.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
W=/tmp/s39c5
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader > $W/gpu.txt 2>&1
mkdir -p /tmp/old  # (kept on a warm machine: its build is then incremental)
tar cf - --exclude=./build-gpu --exclude=./.gpu-data . | tar xf - -C /tmp/old
sed -i 's/^    vertices_only = same_triangles/    vertices_only = false \&\& same_triangles/' \
  /tmp/old/src/fcl/fcl_collide.cpp
grep -c 'vertices_only = false && same_triangles' /tmp/old/src/fcl/fcl_collide.cpp > $W/mutant.txt
CONF=(-DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L"
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc -DKDET_FCL_BUILD_TESTS=OFF)
for v in new old; do
  case $v in new) S=$PWD ;; old) S=/tmp/old ;; esac
  (cmake -S $S -B $S/build-gpu "${CONF[@]}" > $W/build-$v.log 2>&1 &&
   cmake --build $S/build-gpu --parallel 8 --target kdet_fcl >> $W/build-$v.log 2>&1 &&
   g++ -O2 -std=c++17 -I $S/include -isystem $D/usr/include -isystem $D/usr/include/x86_64-linux-gnu \
     -isystem /usr/include/eigen3 benchmarks/results/gpu-session39/fcl_gpu_probe.cpp \
     -L $S/build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath -Wl,--allow-shlib-undefined -o $W/probe-$v >> $W/build-$v.log 2>&1
   echo "build $v rc=$?" >> $T) &
done
wait
date >> $T
for r in 1 2 3; do
  for v in new old; do
    case $v in new) S=$PWD ;; old) S=/tmp/old ;; esac
    echo "== $v round $r" >> $W/ab.txt
    LD_LIBRARY_PATH=$L:$S/build-gpu timeout 100 $W/probe-$v 40 >> $W/ab.txt 2>&1
    echo "$v $r rc=$?" >> $T
  done
done
date >> $T
cat $W/ab.txt >> $T
tar czf $OUT/out.tgz -C $W --exclude='probe-*' .
