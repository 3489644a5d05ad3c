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
