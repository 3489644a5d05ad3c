# Sourced by this session's A/B device scripts (call1.sh, call2.sh, call4.sh), which run from the
# repository root of the working tree's copy and carry .fcl-debs/root and .gpu-data.
#   ab_build WORK TARGETS...   the machine into $T (= $OUT/times.txt), configure build-gpu with the
#                              unpacked FCL packages, build the library, then TARGETS in the
#                              background (ab_wait waits for them) while it builds session 42's
#                              frame probe into WORK/probe
#   ab_probe FORMS SCENES...   the probe over FORMS, profiling off, then on (WORK/probe-*.txt)
#   ab_configure WORK          the machine into $T and configure build-gpu (ab_build's first step)
#   ab_wait                    waits for ab_build's background targets
#   ab_targets TARGETS...      builds TARGETS in build-gpu (log $W/build.log, rc into $T)
#   ab_ncu KNOB VALUE FILE     ncu's kernel durations (phase 1's and the counting build's kernels,
#                              no clock control) of gpu_bench's cloth ball under KNOB=VALUE, as
#                              CSV into FILE (session 45)
#   ab_ball KNOB RUNS VALUES...  gpu_bench on the UNC cloth ball, RUNS rounds of one process per
#                              VALUE of KNOB in turn; $OUT/ball.csv, its first column the value
#   ab_check                   the project's GPU check as a user runs it: scripts/gpu_check.sh
#                              with the CUDA tests' and gpu_bench's targets, ctest -L cuda, the
#                              sanitizers and gpu_bench on the cloth ball ($OUT/check,
#                              $OUT/gpu_check.log; session 44's call 3, session 45's call 4)
#   ab_table                   kdet_bench's GPU table of the UNC and cloth scenes (1M included,
#                              the LBVH in the same process) into $W/bench and $W/bench.log,
#                              its disagreements (and, from session 46, UNSTEADY lines) into $T,
#                              gpu_table.py's table into $OUT/table.md (session 45's call 5,
#                              session 46's calls 3 and 5)
#   ab_finish                  the probes' outputs and the logs (out.tgz) into $OUT
#   ab_gtest NAME FILTER       test_cuda_query on FILTER into $W/test-NAME.txt, its rc and its
#                              OK/FAILED lines into $T (sessions 46 and 47)
#   ab_without DIFF NAME FILTER  DIFF applied (a fix taken back), test_cuda_query rebuilt and run
#                              by ab_gtest (its failures' lines into $T too), DIFF taken back and
#                              test_cuda_query rebuilt again, so that the machine's build-gpu does
#                              not keep the library without the fix (session 47's call 2 met that
#                              trap; its call 1 ran these steps without the last rebuild)
set -u
T=$OUT/times.txt
D=$PWD/.fcl-debs/root
L=$D/usr/lib/x86_64-linux-gnu
export KDET_FCL_DATA_DIR=$PWD/.gpu-data
export LD_LIBRARY_PATH=$L:$PWD/build-gpu

ab_configure() {
  W=$1
  mkdir -p $W
  date > $T
  nproc >> $T
  nvidia-smi --query-gpu=name,memory.total --format=csv >> $T 2>&1
  cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$D/usr -Dccd_DIR=$L/ccd \
    -Doctomap_DIR=$D/usr/share/octomap -DKDET_FCL_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
    -DKDET_FCL_CUDA_ARCHITECTURES=90 -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
    "-DCMAKE_CXX_FLAGS=-isystem $D/usr/include/x86_64-linux-gnu" "-DCMAKE_EXE_LINKER_FLAGS=-L$L" \
    -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc > $W/build.log 2>&1
}

ab_build() {
  ab_configure $1
  shift
  cmake --build build-gpu --parallel 16 --target kdet_fcl >> $W/build.log 2>&1
  echo "lib rc=$? $(date +%T)" >> $T
  (cmake --build build-gpu --parallel 12 --target "$@" > $W/build2.log 2>&1
   echo "bench+test build rc=$? $(date +%T)" >> $T) &
  AB_BG=$!
  local P=benchmarks/results/gpu-session42  # the frame probe of session 42, unchanged
  g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
    -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 $P/frame_probe.cpp \
    benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath \
    -Wl,--allow-shlib-undefined -o $W/probe > $W/probe-build.log 2>&1
  echo "probe build rc=$? $(date +%T)" >> $T
}

ab_probe() {
  local forms=$1
  shift
  FORMS="$forms" ROUNDS=13 timeout 150 $W/probe "$@" > $W/probe-off.txt 2>&1
  echo "probe off rc=$? $(date +%T)" >> $T
  PROFILE=1 FORMS="$forms" ROUNDS=13 timeout 150 $W/probe "$@" > $W/probe-on.txt 2>&1
  echo "probe on rc=$? $(date +%T)" >> $T
}

ab_wait() { wait $AB_BG; }

ab_targets() {
  cmake --build build-gpu --parallel 16 --target "$@" >> $W/build.log 2>&1
  echo "build rc=$? $(date +%T)" >> $T
}

ab_ball() {
  local knob=$1 runs=$2 name=${1#KDET_FCL_CUDA_}
  shift 2
  for r in $(seq $runs); do
    for w in "$@"; do
      env $knob=$w timeout 60 build-gpu/benchmarks/gpu_bench --data $KDET_FCL_DATA_DIR --no-fcl \
        --no-cpu --repeats 20 --only unc-cloth-ball --csv $W/ball-$w-$r.csv >> $W/ball.log 2>&1
      echo "cloth ball $name=$w $r rc=$? $(date +%T)" >> $T
      if [ ! -f $OUT/ball.csv ]; then
        head -1 $W/ball-$w-$r.csv | sed "s/^/$name,process,/" > $OUT/ball.csv
      fi
      tail -n +2 $W/ball-$w-$r.csv | sed "s/^/$w,$r,/" >> $OUT/ball.csv
    done
  done
}

ab_ncu() {
  local knob=$1 value=$2 file=$3
  env $knob=$value timeout 120 $(command -v ncu || echo /usr/local/cuda/bin/ncu) \
    --clock-control none \
    -k 'regex:selfCandidatesWarp|selfCellPairs|interCandidatesWarp|countFill|countCells|scatterKernel|countClear' \
    --metrics gpu__time_duration.sum --csv --print-units base \
    build-gpu/benchmarks/gpu_bench --data $KDET_FCL_DATA_DIR --no-fcl --no-cpu --repeats 10 \
    --only unc-cloth-ball > $file 2> ${file%.csv}.err
  echo "ncu ${knob#KDET_FCL_CUDA_}=$value rc=$? $(date +%T)" >> $T
}

ab_check() {
  date > $T
  OUT=$OUT/check CTEST_ALL=0 SANITIZER=1 GPU_BENCH=1 \
    GPU_BENCH_ARGS="--no-fcl --no-cpu --repeats 20 --only unc-cloth-ball" \
    TARGETS="test_cuda_device test_cuda_query test_cuda_bvh test_cuda_upload test_cuda_box_test test_cuda_warp_search test_cuda_predicates gpu_bench" \
    timeout 570 scripts/gpu_check.sh > $OUT/gpu_check.log 2>&1
  echo "gpu_check rc=$? $(date +%T)" >> $T
  gzip -f $OUT/check/ctest.log $OUT/check/build.log 2>/dev/null
  date >> $T
}

ab_table() {
  timeout 130 build-gpu/benchmarks/kdet_bench --reps 5 --frames 5 --rep-budget 5 --no-kfree \
    --no-plots --methods 'kdet_gpu$,gpu_bvh$' --include-1m --only unc,cloth --out $W/bench \
    > $W/bench.log 2>&1
  echo "kdet_bench rc=$? $(date +%T)" >> $T
  grep -h "DISAGREEMENT \*\*\*\|UNSTEADY" $W/bench.log >> $T
  python3 benchmarks/results/gpu-h100-session37/gpu_table.py $W/bench/bench.json \
    > $OUT/table.md 2>&1
}

ab_finish() {
  date >> $T
  cp $W/probe-*.txt $OUT/
  tar czf $OUT/out.tgz -C $W --exclude=probe --exclude='*.csv' .
}

ab_gtest() {
  build-gpu/tests/test_cuda_query --gtest_filter="$2" > $W/test-$1.txt 2>&1
  echo "tests ($1) rc=$? $(date +%T)" >> $T
  grep -E "^\[  (PASSED|FAILED) |^\[       OK|^\[  FAILED" $W/test-$1.txt >> $T
}

ab_without() {
  git apply $1 >> $T 2>&1
  echo "$1 applied rc=$? $(date +%T)" >> $T
  ab_targets test_cuda_query
  ab_gtest $2 "$3"
  grep -E "Failure|Which is" $W/test-$2.txt | head -60 >> $T
  git apply -R $1
  ab_targets test_cuda_query
}
