#!/usr/bin/env bash
# Builds (scripts/setup.sh) and runs the demo: ${BUILD_DIR:-build}/kdet demo [args...]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
"$ROOT/scripts/setup.sh"
exec "${BUILD_DIR:-build}/kdet" demo "$@"
