#!/usr/bin/env bash
# Session 54's device call (carry .fcl-debs/root and .gpu-data; run from the checkout's root):
#   calls.sh python   (fresh machine, about 5 minutes) scripts/gpu_check.sh building the library,
#                     the Python module (the device image's python3 has pybind11 and NumPy) and
#                     the CUDA test programs of ctest -L cuda (python_cuda among them), then
#                     ctest -L python, and benchmarks/python_bench.py with its GPU rows, into $OUT
#   calls.sh bench    (fresh machine) the module built, the first-contact probe and python_bench
#   calls.sh pytests  (the same machine) reconfigure, then ctest -L python alone
#   calls.sh debug    the same build (and test_cuda_query for ctest -L cuda), then the quick start
#                     and the Python tests under faulthandler and cuda-gdb, into $OUT/debug.txt
set -uo pipefail
cd "$(dirname "$0")/../../.."
OUT="${OUT:-gpu-logs}"; mkdir -p "$OUT"
DEBS="$PWD/.fcl-debs/root"; LIB="$DEBS/usr/lib/x86_64-linux-gnu"
case "${1:-}" in
  python)
    {
      python3 -c "import sys, numpy, pybind11; print(sys.version.split()[0], 'numpy', numpy.__version__, 'pybind11', pybind11.__version__)"
      OUT="$OUT" TARGETS="kdet_fcl _kdet_fcl test_cuda_device test_backend test_cuda_query" \
        CTEST_ALL=0 scripts/gpu_check.sh
      echo "gpu_check exit $?"
      export LD_LIBRARY_PATH="$LIB${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
      ctest --test-dir build-gpu -L python --output-on-failure -V 2>&1 | grep -E "GPU:|ok$|OK|FAIL|ERROR|Error|tests passed|Test +#|skipped" | head -n 80
      # The Python tests' preload (gpu_check.sh finds whether this python3 needs one).
      preload=$(sed -n 's/^KDET_FCL_PYTHON_TEST_PRELOAD:FILEPATH=//p' build-gpu/CMakeCache.txt)
      echo "preload: ${preload:-none}"
      echo "== toolchain: CXX=${CXX:-}"; file -L "${CXX:-/usr/bin/c++}" | cut -c1-200
      grep -a -o -E "static-libstdc\+\+|-Wl,[^ \"]*|-static[^ \"]*" "${CXX:-/usr/bin/c++}" 2>/dev/null | sort | uniq -c | head
      echo "libstdc++ parts defined in libkdet_fcl.so: $(nm -D --defined-only build-gpu/libkdet_fcl.so.0 | grep -c -E 'codecvt|_ZNSo9_M_insert|locale')"
      echo "the same in a local build of Debian's g++ 12 had 0 (undefined: they come from libstdc++.so.6)"
      LD_PRELOAD="$preload" KDET_FCL_SHARED_DATA="$PWD/.gpu-data" PYTHONPATH=build-gpu/python \
        python3 benchmarks/python_bench.py --repeats 25 --json "$OUT/python_bench.json" \
        >"$OUT/python_bench.md" 2>"$OUT/python_bench.err"
      echo "python_bench exit $?"
      cat "$OUT/python_bench.md"
    } >"$OUT/python.txt" 2>&1
    tail -n 80 "$OUT/python.txt" ;;
  bench)
    # (fresh machine, about 4 minutes) the library and the Python module only, then
    # benchmarks/python_bench.py (with the capped queries' first chunks on the calling thread)
    # and the first-contact probe by thread count, into $OUT/bench.txt
    {
      OUT="$OUT/re" TARGETS="_kdet_fcl" CTEST_ALL=0 scripts/gpu_check.sh >/dev/null 2>&1
      echo "gpu_check exit $? (ctest -L cuda of a partial build: not the check)"
      export LD_LIBRARY_PATH="$LIB${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
      preload=$(sed -n 's/^KDET_FCL_PYTHON_TEST_PRELOAD:FILEPATH=//p' build-gpu/CMakeCache.txt)
      export LD_PRELOAD="$preload" PYTHONPATH=build-gpu/python
      ctest --test-dir build-gpu -L python 2>&1 | grep -E "tests passed|Failed"
      python3 benchmarks/results/gpu-session54/first_contact_probe.py
      python3 benchmarks/python_bench.py --repeats 25 --json "$OUT/python_bench.json" \
        >"$OUT/python_bench.md" 2>/dev/null
      echo "python_bench exit $?"
      cat "$OUT/python_bench.md"
    } >"$OUT/bench.txt" 2>&1
    cat "$OUT/bench.txt" ;;
  pytests)
    # (the machine of a `python` call) the build reconfigured as gpu_check.sh configures it, then
    # ctest -L python alone, into $OUT/pytests.txt
    {
      OUT="$OUT/re" TARGETS="_kdet_fcl" CTEST_ALL=0 scripts/gpu_check.sh >/dev/null 2>&1
      export LD_LIBRARY_PATH="$LIB${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
      ctest --test-dir build-gpu -L python --output-on-failure 2>&1 | tail -n 25
    } >"$OUT/pytests.txt" 2>&1
    cat "$OUT/pytests.txt" ;;
  debug)
    # Where the Python tests crash: the module built alone, then the tests and the quick start
    # under faulthandler (Python's stack at a fault) and cuda-gdb (the native stack).
    {
      OUT="$OUT" TARGETS="kdet_fcl _kdet_fcl test_cuda_device test_backend test_cuda_query" \
        CTEST_ALL=0 scripts/gpu_check.sh
      echo "gpu_check exit $?"
      export LD_LIBRARY_PATH="$LIB${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
      export PYTHONPATH="$PWD/build-gpu/python" PYTHONUNBUFFERED=1
      echo "== env"; env | grep -i -E "^python|^LD_" ; python3 -c "import pybind11; print(pybind11.__version__)"
      echo "== quickstart, faulthandler"; python3 -X faulthandler examples/quickstart.py; echo "exit $?"
      echo "== quickstart, cuda-gdb"
      timeout 300 cuda-gdb -q -batch -ex run -ex bt -ex "info threads" --args python3 examples/quickstart.py 2>&1 | grep -v "^\[New Thread\|^\[Thread .* exited" | tail -n 60
      echo "== unittest, faulthandler"
      (cd python/tests && python3 -X faulthandler -m unittest -v test_python 2>&1 | tail -n 60)
    } >"$OUT/debug.txt" 2>&1
    tail -n 150 "$OUT/debug.txt" ;;
  *) echo "usage: calls.sh python|bench|pytests|debug" >&2; exit 2 ;;
esac
