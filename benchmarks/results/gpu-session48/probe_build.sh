# Sourced after ../gpu-session44/ab_common.sh by this session's device scripts (call3.sh, call5.sh,
# call7.sh, next_check.sh; their runs had this command inline, moved here after them):
#   probe_build [SRC BIN]  SRC (default precision_probe.cpp) against build-gpu's library into
#                 BIN (default $W/probe; log BIN-build.log, rc into $T). Session 49's call3.sh and
#                 call4.sh build forward_probe.cpp with it (their runs had the command inline).
probe_build() {
  local src=${1:-benchmarks/results/gpu-session48/precision_probe.cpp} bin=${2:-$W/probe}
  g++ -O2 -std=c++17 -I include -I src -I . -I build-gpu -I benchmarks -isystem $D/usr/include \
    -isystem $D/usr/include/x86_64-linux-gnu -isystem /usr/include/eigen3 \
    $src benchmarks/bench_scenes.cpp \
    -L build-gpu -lkdet_fcl -L$L -lfcl -lccd -loctomap -loctomath -Wl,--allow-shlib-undefined \
    -o $bin > $bin-build.log 2>&1
  echo "probe build rc=$? $(date +%T)" >> $T
}

# forward_ab KNOB TAG ON OFF  session 49's forward probe ($W/fprobe) with KNOB=1 and KNOB=0 in
#               turn: the 90k cloth (20 frames) in ON processes with 1 and OFF with 0
#               ($OUT/fwd-90k-TAG<value>-<round>.txt), then the 250k cloth (12 frames) once each
#               ($W/fwd-250k-TAG<value>.txt); rcs into $T. Session 49's call3.sh (KNOB
#               KDET_FCL_CUDA_GRAPH_UPDATE, TAG u, 2 2) and session 50's (KDET_FCL_CUDA_PIN_VERTICES,
#               pin, 3 2) ran these loops inline, moved here after them.
forward_ab() {
  local knob=$1 tag=$2 on=$3 off=$4 r v
  for r in $(seq 1 $((on > off ? on : off))); do
    for v in 1 0; do
      { [ $v = 1 ] && [ $r -gt $on ]; } || { [ $v = 0 ] && [ $r -gt $off ]; } && continue
      env $knob=$v FRAMES=20 timeout 60 $W/fprobe cloth-90k 2>&1 | grep -v "^kdet_bench:" \
        > $OUT/fwd-90k-$tag$v-$r.txt
      echo "forward 90k $knob=$v $r rc=${PIPESTATUS[0]} $(date +%T)" >> $T
    done
  done
  for v in 1 0; do
    env $knob=$v FRAMES=12 timeout 90 $W/fprobe cloth-250k 2>&1 | grep -v "^kdet_bench:" \
      > $W/fwd-250k-$tag$v.txt
    echo "forward 250k $knob=$v rc=${PIPESTATUS[0]} $(date +%T)" >> $T
  done
}

# forward_probe_build [DIFF...]  session 49's forward_probe.cpp copied to $W, the DIFFs applied to
#               it in turn (log $W/patch.log, rc into $T), built by probe_build into $W/fprobe.
#               Session 50's call3.sh (its forward_probe.diff) and session 51's call1.sh and
#               call5.sh (session 50's diff, then their own) ran these lines inline, moved here
#               after them.
forward_probe_build() {
  local d ok=0
  cp benchmarks/results/gpu-session49/forward_probe.cpp $W/forward_probe.cpp
  for d in "$@"; do
    (cd $W && git apply -p0 $OLDPWD/$d) >> $W/patch.log 2>&1 || ok=1
  done
  echo "forward_probe diffs applied rc=$ok $(date +%T)" >> $T
  probe_build $W/forward_probe.cpp $W/fprobe
}

# forward_runs KNOB TAG SCENE FRAMES ROUNDS LIMIT  $W/fprobe on SCENE (FRAMES frames), ROUNDS
#               rounds of one process with KNOB=1 and one with KNOB=0, each under `timeout LIMIT`,
#               into $W/fwd-<SCENE less "cloth-">-TAG<value>-<round>.txt; rcs into $T. Session 51's
#               call5.sh ran these loops inline, moved here after it.
forward_runs() {
  local knob=$1 tag=$2 scene=$3 frames=$4 rounds=$5 limit=$6 r v
  for r in $(seq $rounds); do
    for v in 1 0; do
      env $knob=$v FRAMES=$frames timeout $limit $W/fprobe $scene 2>&1 | grep -v "^kdet_bench:" \
        > $W/fwd-${scene#cloth-}-$tag$v-$r.txt
      echo "forward ${scene#cloth-} $tag=$v $r rc=${PIPESTATUS[0]} $(date +%T)" >> $T
    done
  done
}
