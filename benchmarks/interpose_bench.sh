#!/usr/bin/env bash
# An unmodified FCL program with and without kDet underneath: example_unmodified_fcl's bench mode
# (an 80k-triangle sheet against a 20k-triangle sphere, OBBRSS, every pair; rigid checks, then
# deforming frames through FCL's beginUpdateModel/updateVertex/endUpdateModel) run as it is and
# under LD_PRELOAD=libkdet_fcl_interpose.so, in alternating processes. Prints each run's medians
# and, at the end, the median of each form and their ratio.
#
#   benchmarks/interpose_bench.sh [build dir (build)] [rounds (3)] [checks per run (15)]
# Extra environment goes to the preloaded runs, e.g. KDET_FCL_INTERPOSE_BACKEND=cuda.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${1:-$ROOT/build}"
ROUNDS="${2:-3}"
CHECKS="${3:-15}"
APP="$BUILD/example_unmodified_fcl"
SHIM="$BUILD/libkdet_fcl_interpose.so"
for f in "$APP" "$SHIM"; do
  [[ -e "$f" ]] || { echo "interpose_bench: $f not found (build the project first)" >&2; exit 1; }
done
[[ "$ROUNDS" =~ ^[1-9][0-9]*$ ]] || { echo "interpose_bench: rounds must be a positive integer" >&2; exit 2; }
echo "host: $(nproc) threads, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
echo "backend under the library: ${KDET_FCL_INTERPOSE_BACKEND:-cpu}"

declare -a fcl_rigid fcl_deform fcl_check kdet_rigid kdet_deform kdet_check
field() { sed -n "s/^bench $1: median \([0-9.]*\) ms.*/\1/p"; }
check_of() { sed -n "s/^bench deforming: .* + check \([0-9.]*\) ms.*/\1/p"; }
for ((r = 1; r <= ROUNDS; ++r)); do
  out=$("$APP" bench "$CHECKS")
  fcl_rigid+=("$(field rigid <<<"$out")"); fcl_deform+=("$(field deforming <<<"$out")")
  fcl_check+=("$(check_of <<<"$out")")
  echo "round $r, FCL alone:         rigid ${fcl_rigid[-1]} ms, deforming ${fcl_deform[-1]} ms (check ${fcl_check[-1]})"
  out=$(LD_PRELOAD="$SHIM" KDET_FCL_INTERPOSE_STATS=1 "$APP" bench "$CHECKS" 2>"$BUILD/interpose_bench.err")
  kdet_rigid+=("$(field rigid <<<"$out")"); kdet_deform+=("$(field deforming <<<"$out")")
  kdet_check+=("$(check_of <<<"$out")")
  echo "round $r, under the library: rigid ${kdet_rigid[-1]} ms, deforming ${kdet_deform[-1]} ms (check ${kdet_check[-1]})"
  grep -q "fell back to FCL 0" "$BUILD/interpose_bench.err" ||
    { echo "interpose_bench: kDet refused a pair:" >&2; cat "$BUILD/interpose_bench.err" >&2; exit 1; }
done
tail -n1 "$BUILD/interpose_bench.err"
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
fr=$(median "${fcl_rigid[@]}"); kr=$(median "${kdet_rigid[@]}")
fd=$(median "${fcl_deform[@]}"); kd=$(median "${kdet_deform[@]}")
fc=$(median "${fcl_check[@]}"); kc=$(median "${kdet_check[@]}")
awk -v fr="$fr" -v kr="$kr" -v fd="$fd" -v kd="$kd" -v fc="$fc" -v kc="$kc" 'BEGIN {
  printf "medians over the rounds: rigid check %.3f ms alone, %.3f ms under the library (%.2fx)\n", fr, kr, fr / kr
  printf "                         deforming frame %.3f ms alone, %.3f ms under the library (%.2fx; FCL'\''s refit in both)\n", fd, kd, fd / kd
  printf "                         of it the check after the update %.3f ms alone, %.3f ms under the library (%.2fx)\n", fc, kc, fc / kc }'
