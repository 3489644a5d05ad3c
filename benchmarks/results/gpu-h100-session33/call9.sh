#!/bin/bash
# Device call 9 (carry .fcl-debs and .gpu-data; 600 s): an instruction-level account of the
# cloth ball's phase-1 kernels on the tree with the queue of seen entries (bc46184): gpu_bench
# built with -lineinfo (no change to the code generated); ncu's source counters (and warp
# states) of one launch each of the warp scan and the cells' pairs of the cloth ball's self
# query, exported per SASS instruction and per CUDA line.
set -u
cd "$(dirname "$0")/../../.."
T=$OUT/times.txt
date > $T
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
W=/tmp/c9
mkdir -p $W
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=$L
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
  -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
  -DCMAKE_CUDA_FLAGS=-lineinfo -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
cmake --build build-gpu --parallel 16 --target gpu_bench >> $W/build.log 2>&1
echo "build rc=$?" >> $T
date >> $T
B=build-gpu/benchmarks/gpu_bench
NCU=$(command -v ncu || echo /usr/local/cuda/bin/ncu)
prof() {  # name, kernel regex, launches to skip
  timeout 150 $NCU --clock-control none --kernel-name-base demangled --kernel-name regex:"$2" \
    --launch-skip $3 --launch-count 1 --section SourceCounters --section WarpStateStats \
    --section LaunchStats --section Occupancy --section SpeedOfLight --import-source yes \
    -o $W/$1 $B --no-fcl --no-cpu --repeats 3 --only unc-cloth-ball-self > $W/ncu-$1.log 2>&1
  echo "ncu $1 rc=$?" >> $T
  $NCU -i $W/$1.ncu-rep --page source --csv --print-source sass > $W/$1-sass.csv 2>&1
  $NCU -i $W/$1.ncu-rep --page source --csv --print-source cuda > $W/$1-cuda.csv 2>&1
  $NCU -i $W/$1.ncu-rep --page details >> $W/details.txt 2>&1
}
prof scan 'kdet_fcl::cuda.*selfCandidatesWarpKernel' 4
prof cells 'kdet_fcl::cuda.*selfCellPairsKernel' 4
date >> $T
cd $W && tar czf $OUT/source.tgz *-sass.csv *-cuda.csv details.txt *.log
date >> $T
