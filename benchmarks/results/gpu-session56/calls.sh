#!/usr/bin/env bash
# Session 56's device calls (carry .fcl-debs/root and .gpu-data; run from the checkout's root):
#   calls.sh check   (fresh machine, about 7 minutes) the project's GPU check as a user runs it:
#                    scripts/gpu_check.sh with ctest -L cuda (with this session's scale ladder,
#                    CudaQueryTyped.PairsAreTheSameAtEveryScaleOfTheExactRange, and the commit
#                    refused for its scale), memcheck and gpu_bench on the cloth ball, into
#                    $OUT/check (session 53's calls.sh check: session 49's next_check.sh check)
#   calls.sh range   (the same machine; build-gpu reused) the CPU-side tests of the change on
#                    the GPU machine: the bad-input, extremes, FCL collide and manager tests, into
#                    $OUT/range.txt
#   calls.sh final   (fresh machine, about 6 minutes) the final tree: scripts/gpu_check.sh with
#                    ctest -L cuda (no sanitizer, no benchmark), then the FCL drop-in's tests
#                    (test_fcl_guarded, test_fcl_collide, test_fcl_manager, test_bad_input) and
#                    the interposer's, into $OUT/final
set -uo pipefail
cd "$(dirname "$0")/../../.."
OUT="${OUT:-gpu-logs}"; mkdir -p "$OUT"
LIB="$PWD/.fcl-debs/root/usr/lib/x86_64-linux-gnu"
case "${1:-}" in
  check) bash benchmarks/results/gpu-session53/calls.sh check ;;  # the same check as then
  range)
    export LD_LIBRARY_PATH="$LIB${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    {
      nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv
      cmake --build build-gpu -j"$(nproc)" --target test_bad_input test_extremes \
        test_fcl_collide test_fcl_manager >/dev/null && echo "build OK"
      for t in test_bad_input test_extremes test_fcl_collide test_fcl_manager; do
        echo "== $t"; build-gpu/tests/$t 2>&1 | tail -n 3
      done
    } >"$OUT/range.txt" 2>&1
    cat "$OUT/range.txt" ;;
  final)
    OUT=$OUT/final CTEST_ALL=0 JOBS=16 TARGETS="test_cuda_device test_cuda_query test_cuda_bvh \
      test_cuda_upload test_cuda_box_test test_cuda_warp_search test_cuda_predicates \
      test_fcl_guarded test_fcl_collide test_fcl_manager test_bad_input" \
      timeout 480 scripts/gpu_check.sh > "$OUT/gpu_check-final.log" 2>&1
    echo "gpu_check rc=$?"
    export LD_LIBRARY_PATH="$LIB${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    ctest --test-dir build-gpu -R 'FclGuarded|FclCollideBadInput|FclManager|BadInput|interpose' \
      -j 8 > "$OUT/final/fcl.txt" 2>&1
    echo "fcl tests rc=$?"
    tail -n 5 "$OUT/gpu_check-final.log"; tail -n 4 "$OUT/final/fcl.txt"
    gzip -f "$OUT"/final/*.log 2>/dev/null ;;
  *) echo "usage: calls.sh check|range|final" >&2; exit 2 ;;
esac
