#!/usr/bin/env bash
# Session 53's device calls (carry .fcl-debs/root and .gpu-data; run from the checkout's root):
#   calls.sh check       (fresh machine, about 7 minutes) the project's GPU check as a user runs
#                        it: scripts/gpu_check.sh with ctest -L cuda, memcheck and gpu_bench on
#                        the cloth ball, into $OUT/check (session 49's next_check.sh check)
#   calls.sh interpose   (the same machine; the check's build-gpu reused) ctest -R interpose,
#                        benchmarks/interpose_bench.sh with the CPU backend, the CPU backend and
#                        the trust cache, and the CUDA backend, and checksum_probe (the vector
#                        checksum against the scalar one it replaced, by size and threads), into
#                        $OUT/interpose.txt
#   calls.sh probe       checksum_probe alone (built from its sources in a few seconds; no GPU
#                        needed, but the machine's Xeon), with the CPU's model and flags, into
#                        $OUT/probe.txt
#   calls.sh rounds      (any machine) a CPU-only build of the interposer (build-cpu), then
#                        interpose_bench.sh five rounds with the checksum and five with the trust
#                        cache, alternating, into $OUT/rounds.txt: their difference is the
#                        checksum's cost inside the program
set -uo pipefail
cd "$(dirname "$0")/../../.."
OUT="${OUT:-gpu-logs}"; mkdir -p "$OUT"
DEBS="$PWD/.fcl-debs/root"; LIB="$DEBS/usr/lib/x86_64-linux-gnu"
case "${1:-}" in
  check)
    bash benchmarks/results/gpu-session49/next_check.sh check
    tail -n 30 "$OUT/gpu_check.log" ;;
  interpose)
    export LD_LIBRARY_PATH="$LIB${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    {
      nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv
      echo "host threads: $(nproc)"
      cmake --build build-gpu -j"$(nproc)" --target kdet_fcl_interpose example_unmodified_fcl \
        >/dev/null && echo "build OK"
      ctest --test-dir build-gpu -R interpose --output-on-failure | tail -n 6
      g++ -O3 -std=c++17 -Isrc -Iinclude benchmarks/results/cpu-interpose/checksum_probe.cpp \
        -o build-gpu/checksum_probe -Lbuild-gpu -lkdet_fcl -Wl,-rpath,"$PWD/build-gpu" &&
        echo "== checksum_probe" && build-gpu/checksum_probe
      echo "== bench, CPU backend"
      benchmarks/interpose_bench.sh build-gpu 3 15
      echo "== bench, CPU backend, cache trust"
      KDET_FCL_INTERPOSE_CACHE=trust benchmarks/interpose_bench.sh build-gpu 3 15
      echo "== bench, CUDA backend"
      KDET_FCL_INTERPOSE_BACKEND=cuda benchmarks/interpose_bench.sh build-gpu 3 15
    } >"$OUT/interpose.txt" 2>&1
    tail -n 60 "$OUT/interpose.txt" ;;
  probe)
    {
      lscpu | grep -E "Model name|Thread|Core|Socket|MHz|L1d|L2|L3|Flags" | cut -c1-300
      g++ -O3 -std=c++17 -Isrc -Iinclude benchmarks/results/cpu-interpose/checksum_probe.cpp \
        src/fcl/checksum.cpp src/cpu/worker_pool.cpp -pthread -o /tmp/checksum_probe &&
        /tmp/checksum_probe && /tmp/checksum_probe
    } >"$OUT/probe.txt" 2>&1
    cat "$OUT/probe.txt" ;;
  rounds)
    export LD_LIBRARY_PATH="$LIB${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    {
      cmake -S . -B build-cpu -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=$DEBS/usr" \
        "-Dccd_DIR=$LIB/ccd" "-Doctomap_DIR=$DEBS/usr/share/octomap" -DKDET_FCL_CUDA=OFF \
        -DCMAKE_POLICY_VERSION_MINIMUM=3.5 -DKDET_FCL_BUILD_BENCHMARKS=OFF >/dev/null &&
        cmake --build build-cpu -j"$(nproc)" --target kdet_fcl_interpose example_unmodified_fcl \
          >/dev/null && echo "build OK"
      for r in 1 2; do
        echo "== checksum, set $r"; benchmarks/interpose_bench.sh build-cpu 5 15 | tail -n 5
        echo "== trust, set $r"
        KDET_FCL_INTERPOSE_CACHE=trust benchmarks/interpose_bench.sh build-cpu 5 15 | tail -n 5
      done
    } >"$OUT/rounds.txt" 2>&1
    cat "$OUT/rounds.txt" ;;
  *) echo "usage: calls.sh check|interpose|probe|rounds" >&2; exit 2 ;;
esac
