#!/bin/bash
# Device call 3 of session 47 (carry .fcl-debs/root and .gpu-data), on a fresh machine: call 2
# again. Call 2 ran on call 1's machine, whose build-gpu still held the library built with
# nofix.diff (the restored source was older than that build, so nothing was rebuilt): its new
# test failed as in call 1's unfixed run. Here the GPU check builds everything anew.
cd "$(dirname "$0")/../../.."
. benchmarks/results/gpu-session44/ab_common.sh
rm -rf build-gpu
ab_check
