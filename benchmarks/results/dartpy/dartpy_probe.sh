#!/usr/bin/env bash
# Runs dartpy_probe.py with DART's default contact points and with DART's FCL contact points,
# each plain and under LD_PRELOAD=libkdet_fcl_interpose.so, then compares each pair of runs
# with the exact pairs. Needs Debian's python3-dartpy and python3-numpy (/usr/bin/python3).
#   benchmarks/results/dartpy/dartpy_probe.sh [build dir (build)] [output dir (this folder)]
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
BUILD="$(cd "${1:-$HERE/../../../build}" && pwd)"
OUTDIR="${2:-$HERE}"
PY=/usr/bin/python3
"$PY" -c "import dartpy" 2>/dev/null || { echo "dartpy_probe: python3-dartpy is not installed" >&2; exit 1; }
for contacts in dart fcl; do
  echo "== DART's $contacts contact points, FCL alone"
  PROBE_CONTACTS=$contacts "$PY" "$HERE/dartpy_probe.py" run "$OUTDIR/$contacts-fcl.json"
  echo "== DART's $contacts contact points, under the library"
  PROBE_CONTACTS=$contacts KDET_FCL_INTERPOSE_STATS=1 LD_PRELOAD="$BUILD/libkdet_fcl_interpose.so" \
    "$PY" "$HERE/dartpy_probe.py" run "$OUTDIR/$contacts-kdet.json"
  echo "== compared with the exact pairs"
  "$PY" "$HERE/dartpy_probe.py" compare "$OUTDIR/$contacts-fcl.json" "$OUTDIR/$contacts-kdet.json" || true
done
