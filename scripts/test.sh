#!/usr/bin/env bash
# Builds (scripts/setup.sh) and runs the test suite; extra arguments go to ctest, e.g.
#   scripts/test.sh -L unit        scripts/test.sh -R Backend -V
# The exit status is ctest's.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
"$ROOT/scripts/setup.sh"
exec ctest --test-dir "${BUILD_DIR:-build}" --output-on-failure -j2 "$@"
