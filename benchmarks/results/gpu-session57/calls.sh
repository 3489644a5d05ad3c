#!/usr/bin/env bash
# Session 57's device calls (carry .fcl-debs/root and .gpu-data; run from the checkout's root).
#   calls.sh probe   (nvidia-h200-x2, two GPUs) builds the library alone and runs device_probe.cpp:
#                    a GPU query from a caller whose current CUDA device is 1, from another
#                    thread, and on device 0; prints what the caller's device is after each,
#                    into $OUT/probe.txt
#   calls.sh check   (nvidia-h200-x2, fresh, about 8 minutes) the GPU check of the tree with the
#                    backend's device chosen and kept per call: scripts/gpu_check.sh (ctest -L
#                    cuda with test_cuda_devices on two GPUs, memcheck, gpu_bench on the cloth
#                    ball) into $OUT/check; then memcheck of test_cuda_devices and the probe
#                    again, into $OUT/extra.txt
#   calls.sh devices (nvidia-h200-x2, fresh, about 4 minutes) the library, test_cuda_devices and
#                    the kdet tool alone: the device tests under ctest and memcheck, and what the
#                    tool prints with --device and KDET_FCL_CUDA_DEVICE, into $OUT/devices.txt
#   calls.sh ab      (nvidia-h200, fresh, about 6 minutes; carry .ab-before too: `git archive` of
#                    the commit before this change, the library's and benchmarks' sources) gpu_bench
#                    of the cloth ball, GPU methods only, from the tree before (build-ab-before)
#                    and this tree (build-ab-after), eight processes alternating, into $OUT/ab.csv
#   calls.sh final   (nvidia-h200-x2, fresh, about 8 minutes) the final tree: scripts/gpu_check.sh
#                    with ctest -L cuda (no sanitizer, no benchmark) into $OUT/final, then gpu_bench
#                    on the cloth ball with KDET_FCL_CUDA_DEVICE=1 while nvidia-smi samples each
#                    GPU's memory, into $OUT/device1.txt
#   calls.sh workers (nvidia-h200-x2, fresh, about 4 minutes) after the worker threads' scopes:
#                    the library, test_cuda_devices, test_cuda_upload and gpu_bench alone; the
#                    device tests and the upload tests under ctest, then gpu_bench on device 1
#                    with nvidia-smi sampling each GPU's memory, into $OUT/workers.txt
set -uo pipefail
cd "$(dirname "$0")/../../.."
OUT="${OUT:-gpu-logs}"; mkdir -p "$OUT"
DEBS="$PWD/.fcl-debs/root"
LIB="$DEBS/usr/lib/x86_64-linux-gnu"
export LD_LIBRARY_PATH="$LIB${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
configure() {  # [source dir] [build dir] [extra args]
  cmake -S "${1:-.}" -B "${2:-build-gpu}" -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=$DEBS/usr" \
    "-Dccd_DIR=$LIB/ccd" "-Doctomap_DIR=$DEBS/usr/share/octomap" -DKDET_FCL_CUDA=ON \
    -DCMAKE_CUDA_ARCHITECTURES=90 -DKDET_FCL_CUDA_ARCHITECTURES=90 \
    -DCMAKE_POLICY_VERSION_MINIMUM=3.5 "-DCMAKE_CXX_FLAGS=-isystem $DEBS/usr/include/x86_64-linux-gnu" \
    "-DCMAKE_EXE_LINKER_FLAGS=-L$LIB" -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc \
    -DKDET_FCL_PYTHON=OFF "${@:3}"
}
probe() {
  g++ -std=c++17 -O2 benchmarks/results/gpu-session57/device_probe.cpp -Iinclude -Lbuild-gpu \
    -lkdet_fcl -I/usr/local/cuda/include -L/usr/local/cuda/lib64 -lcudart -pthread \
    -Wl,-rpath,"$PWD/build-gpu" -o build-gpu/device_probe && build-gpu/device_probe
}
configure_build() {  # the GPUs, then build-gpu configured and the targets built
  nvidia-smi -L
  configure > "$OUT/configure.log" 2>&1 && echo "configured"
  cmake --build build-gpu -j"$(nproc)" --target "$@" > "$OUT/build.log" 2>&1 && echo "built"
}
device1_bench() {  # gpu_bench on device 1 while nvidia-smi samples each GPU's memory
  ( for i in $(seq 1 60); do
      nvidia-smi --query-gpu=index,memory.used --format=csv,noheader,nounits; sleep 0.5
    done > build-gpu/smi.txt ) &
  local smi=$!
  KDET_FCL_CUDA_DEVICE=1 KDET_FCL_DATA_DIR="$PWD/.gpu-data" build-gpu/benchmarks/gpu_bench \
    --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball 2>&1 | grep -E "^device|GPU:|x[0-9]"
  echo "gpu_bench rc=${PIPESTATUS[0]}"
  kill $smi 2>/dev/null; wait $smi 2>/dev/null
  echo "== the most memory each GPU held while it ran (MiB, nvidia-smi every 0.5 s)"
  awk -F', ' '{ if ($2 > m[$1]) m[$1] = $2 } END { for (g in m) print "GPU " g ": " m[g] }' \
    build-gpu/smi.txt | sort
}
case "${1:-}" in
  probe)
    {
      nvidia-smi -L
      date -u
      configure > "$OUT/configure.log" 2>&1 && echo "configured"
      cmake --build build-gpu -j"$(nproc)" --target kdet_fcl > "$OUT/build.log" 2>&1 &&
        echo "library built"
      date -u
      probe
    } > "$OUT/probe.txt" 2>&1
    cat "$OUT/probe.txt"; gzip -f "$OUT"/*.log ;;
  check)
    rm -rf build-gpu
    OUT=$OUT/check CTEST_ALL=0 SANITIZER=1 SANITIZER_TOOLS=memcheck GPU_BENCH=1 JOBS=32 \
      GPU_BENCH_ARGS="--no-fcl --no-cpu --repeats 20 --only unc-cloth-ball" \
      TARGETS="test_cuda_device test_cuda_devices test_cuda_query test_cuda_bvh test_cuda_upload \
        test_cuda_box_test test_cuda_warp_search test_cuda_predicates gpu_bench" \
      timeout 560 scripts/gpu_check.sh > "$OUT/gpu_check.log" 2>&1
    echo "gpu_check rc=$?" >> "$OUT/gpu_check.log"
    {
      SAN="$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)"
      echo "== compute-sanitizer memcheck, test_cuda_devices"
      "$SAN" --tool memcheck --error-exitcode 3 build-gpu/tests/test_cuda_devices 2>&1 | tail -n 12
      echo "memcheck rc=${PIPESTATUS[0]}"
      echo "== device_probe against this tree's library"
      probe
    } > "$OUT/extra.txt" 2>&1
    tail -n 8 "$OUT/gpu_check.log"; cat "$OUT/extra.txt"
    gzip -f "$OUT"/check/*.log 2>/dev/null ;;
  devices)
    {
      configure_build kdet_fcl test_cuda_devices kdet
      ctest --test-dir build-gpu -R 'CudaDevices' --output-on-failure 2>&1 | tail -n 12
      SAN="$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)"
      echo "== compute-sanitizer memcheck, test_cuda_devices"
      "$SAN" --tool memcheck --error-exitcode 3 build-gpu/tests/test_cuda_devices 2>&1 | tail -n 4
      echo "memcheck rc=${PIPESTATUS[0]}"
      printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0.2 0.2 -0.5\nv 0.2 0.2 0.5\nv 0.9 0.9 0\nf 1 2 3\nf 4 5 6\n' \
        > build-gpu/crossing.obj
      for d in 0 1 2; do
        echo "== kdet self crossing.obj --backend cuda --device $d"
        build-gpu/kdet self build-gpu/crossing.obj --backend cuda --device $d; echo "exit $?"
      done
      echo "== KDET_FCL_CUDA_DEVICE=1 kdet info"; KDET_FCL_CUDA_DEVICE=1 build-gpu/kdet info
      echo "== KDET_FCL_CUDA_DEVICE=7 kdet info"; KDET_FCL_CUDA_DEVICE=7 build-gpu/kdet info
      echo "== KDET_FCL_CUDA_DEVICE=7 kdet self --backend cuda"
      KDET_FCL_CUDA_DEVICE=7 build-gpu/kdet self build-gpu/crossing.obj --backend cuda; echo "exit $?"
    } > "$OUT/devices.txt" 2>&1
    cat "$OUT/devices.txt"; gzip -f "$OUT"/*.log ;;
  ab)
    {
      nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv
      lean=(-DKDET_FCL_BUILD_TESTS=OFF -DKDET_FCL_BUILD_CLI=OFF -DKDET_FCL_BUILD_INTERPOSE=OFF)
      configure .ab-before build-ab-before "${lean[@]}" > "$OUT/configure.log" 2>&1 &&
        configure . build-ab-after "${lean[@]}" >> "$OUT/configure.log" 2>&1 && echo "configured"
      ( cmake --build build-ab-before -j8 --target gpu_bench > "$OUT/build-before.log" 2>&1 ) &
      ( cmake --build build-ab-after -j8 --target gpu_bench > "$OUT/build-after.log" 2>&1 ) &
      wait
      ls build-ab-before/benchmarks/gpu_bench build-ab-after/benchmarks/gpu_bench && echo "built"
      export KDET_FCL_DATA_DIR="$PWD/.gpu-data"
      for r in 1 2 3 4; do
        for t in before after; do
          build-ab-$t/benchmarks/gpu_bench --no-fcl --no-cpu --repeats 20 --only unc-cloth-ball \
            --csv "build-ab-$t/r$r.csv" > /dev/null 2>&1 || echo "run $t $r failed"
          tail -n +2 "build-ab-$t/r$r.csv" | sed "s/^/$t,$r,/" >> "$OUT/ab.csv"
        done
      done
      head -n 1 build-ab-after/r1.csv | sed 's/^/tree,round,/' > "$OUT/ab-header.csv"
      python3 - "$OUT/ab-header.csv" "$OUT/ab.csv" <<'PY'
import csv, sys, statistics as st
head = next(csv.reader(open(sys.argv[1])))
rows = [dict(zip(head, r)) for r in csv.reader(open(sys.argv[2]))]
for scene in sorted({r["scene"] for r in rows}):
    for t in ("before", "after"):
        rs = [r for r in rows if r["scene"] == scene and r["tree"] == t]
        f = lambda k: ", ".join("%.3f" % float(r[k]) for r in rs)
        print(scene, t, "| frame:", f("kdet_gpu_ms"), "| on device:", f("kdet_device_ms"),
              "| output:", f("kdet_output_ms"), "| LBVH:", f("lbvh_ms"),
              "| agree:", "".join(r["agree"] for r in rs))
PY
    } > "$OUT/ab.txt" 2>&1
    cat "$OUT/ab.txt"; gzip -f "$OUT"/*.log ;;
  final)
    OUT=$OUT/final CTEST_ALL=0 JOBS=32 \
      TARGETS="test_cuda_device test_cuda_devices test_cuda_query test_cuda_bvh test_cuda_upload \
        test_cuda_box_test test_cuda_warp_search test_cuda_predicates gpu_bench" \
      timeout 500 scripts/gpu_check.sh > "$OUT/gpu_check-final.log" 2>&1
    echo "gpu_check rc=$?" >> "$OUT/gpu_check-final.log"
    {
      device1_bench
    } > "$OUT/device1.txt" 2>&1
    tail -n 6 "$OUT/gpu_check-final.log"; cat "$OUT/device1.txt"
    gzip -f "$OUT"/final/*.log 2>/dev/null ;;
  workers)
    {
      configure_build kdet_fcl test_cuda_devices test_cuda_upload gpu_bench
      ctest --test-dir build-gpu -R '^(CudaDevices[A-Za-z]*|StagedUpload|StagedDownload|PinnedUpload|PooledDownload)[.]' \
        --output-on-failure 2>&1 | tail -n 12
      device1_bench
    } > "$OUT/workers.txt" 2>&1
    cat "$OUT/workers.txt"; gzip -f "$OUT"/*.log ;;
  *) echo "usage: calls.sh probe|check|devices|ab|final|workers" >&2; exit 2 ;;
esac
