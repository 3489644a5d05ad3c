#!/bin/bash
# Device call 3 (carry .fcl-debs/root and .gpu-data; right after call 2, on its warm machine and
# its build-gpu): kdet_bench's GPU methods on every scene (UNC and cloth with 1M, then the rest),
# and update_bench on this host: the final tree against the tree before (pool.diff reversed,
# CPU only), float and double, in alternating rounds.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s39c3
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader > $W/gpu.txt 2>&1
B=build-gpu
[ -x $B/benchmarks/kdet_bench ] || echo "no build-gpu: not the warm machine of call 2" >> $T
M='kdet_gpu$,gpu_bvh$'
timeout 200 $B/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree --no-plots \
  --methods $M --include-1m --only unc,cloth --out $W/part1 > $W/part1.log 2>&1
echo "part1 rc=$?" >> $T
timeout 150 $B/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree --no-plots \
  --methods $M --only fracture,nbody,chair,chazelle,huge,coplanar,rigid --out $W/part2 \
  > $W/part2.log 2>&1
echo "part2 rc=$?" >> $T
date >> $T
tar czf $OUT/out.tgz -C $W .
rm -rf /tmp/base && mkdir -p /tmp/base
tar cf - --exclude=./build-gpu --exclude=./.gpu-data . | tar xf - -C /tmp/base
# (the tree before: the whole library change reversed, pool2.diff = pool.diff plus the vertex split)
(cd /tmp/base && patch -s -R -p1 < benchmarks/results/gpu-session39/pool2.diff)
grep -n '^constexpr.*Vertex' /tmp/base/src/hashed_mesh.cpp > $W/base-constants.txt
CONF=(-DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd
  -Doctomap_DIR=$D/usr/share/octomap -DCMAKE_POLICY_VERSION_MINIMUM=3.5
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L")
cmake -S /tmp/base -B /tmp/base/b "${CONF[@]}" -DKDET_FCL_CUDA=OFF -DKDET_FCL_BUILD_TESTS=OFF \
  > $W/build-base.log 2>&1 && cmake --build /tmp/base/b --parallel 16 --target update_bench \
  >> $W/build-base.log 2>&1
echo "build base rc=$?" >> $T
date >> $T
for r in 1 2 3; do
  for v in base new; do
    case $v in new) U=$B/benchmarks/update_bench ;; *) U=/tmp/base/b/benchmarks/update_bench ;; esac
    for p in float double; do
      a=""; [ $p = double ] && a=--double
      timeout 60 $U --reps 60 $a > $W/update-$v-$p-$r.md 2>&1
    done
  done
done
echo "update_bench done" >> $T
date >> $T
tar czf $OUT/out.tgz -C $W .
