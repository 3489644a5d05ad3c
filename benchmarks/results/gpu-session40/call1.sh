#!/bin/bash
# Device call 1 (carry .fcl-debs/root and .gpu-data): (1) snoop_probe.cu, the DMA of a registered
# host array after it was written, read or flushed by one or many threads (13.5 MB: the 1M cloth's
# positions in double; 3 MB: the 250k cloth's), before anything else loads the host; (2) the
# library and phase_probe.cpp: kdet_bench's cloth frames query by query (QueryProfile); (3) ncu of
# every kernel of the 1M cloth's frames (one round).
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
START=$(date +%s)
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/s40c1
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L:$PWD/build-gpu
P=benchmarks/results/gpu-session40
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader > $W/gpu.txt 2>&1
lscpu > $W/lscpu.txt 2>&1
/usr/local/cuda/bin/nvcc -O3 -std=c++17 -arch=sm_90 -Xcompiler -O3,-march=native $P/snoop_probe.cu -o $W/snoop > $W/snoop-build.log 2>&1
echo "snoop build rc=$?" >> $T
for mb in 13.5 3.0 13.5; do
  timeout 60 $W/snoop $mb 40 >> $W/snoop.txt 2>&1
  echo "snoop $mb rc=$?" >> $T
done
date >> $T
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target kdet_fcl >> $W/build.log 2>&1
echo "build rc=$?" >> $T
g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
  -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 \
  $P/phase_probe.cpp benchmarks/bench_scenes.cpp \
  -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath -Wl,--allow-shlib-undefined -o $W/phase >> $W/build.log 2>&1
echo "phase build rc=$?" >> $T
date >> $T
timeout 150 $W/phase cloth-90k cloth-250k cloth-1000k unc-cloth-ball > $W/phase.txt 2>&1
echo "phase rc=$?" >> $T
date >> $T
left=$((570 - ($(date +%s) - START)))
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
if [ $left -gt 40 ]; then
  ROUNDS=1 timeout $((left - 15)) $NCU --clock-control none --kernel-name-base demangled \
    --metrics gpu__time_duration.sum,launch__grid_size,launch__block_size \
    --csv --print-units base $W/phase cloth-1000k > $W/ncu.csv 2> $W/ncu.err
  echo "ncu rc=$?" >> $T
fi
date >> $T
gzip -f $W/ncu.csv 2>/dev/null
cp $W/snoop.txt $W/phase.txt $OUT/ 2>/dev/null
tar czf $OUT/out.tgz -C $W --exclude=snoop --exclude=phase .
