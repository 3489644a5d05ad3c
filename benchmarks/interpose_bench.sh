#!/usr/bin/env bash
# An unmodified FCL program with and without kDet underneath: example_unmodified_fcl's bench mode
# (a 2.3k-triangle sphere against a 3k-triangle torus at 12 poses, every pair and first contact;
# an 80k-triangle sheet against a 20k-triangle sphere, OBBRSS, every pair: rigid checks, then
# deforming frames through FCL's beginUpdateModel/updateVertex/endUpdateModel) run as it is and
# under LD_PRELOAD=libkdet_fcl_interpose.so, in alternating processes. Prints each run's medians
# and, at the end, the median of each form and their ratio.
#
#   benchmarks/interpose_bench.sh [build dir (build)] [rounds (3)] [checks per run (15)]
# The library's settings come from the environment, e.g. KDET_FCL_INTERPOSE_BACKEND=cuda or
# KDET_FCL_INTERPOSE_CACHE=trust (FCL alone ignores them).
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
echo "under the library: backend ${KDET_FCL_INTERPOSE_BACKEND:-cpu}, cache ${KDET_FCL_INTERPOSE_CACHE:-checksum}"

declare -a fcl_rigid fcl_deform fcl_check kdet_rigid kdet_deform kdet_check
declare -a fcl_small fcl_first kdet_small kdet_first
field() { sed -n "s/^bench $1: median \([0-9.]*\) ms.*/\1/p"; }
check_of() { sed -n "s/^bench deforming: .* + check \([0-9.]*\) ms.*/\1/p"; }
for ((r = 1; r <= ROUNDS; ++r)); do
  out=$("$APP" bench "$CHECKS")
  fcl_rigid+=("$(field rigid <<<"$out")"); fcl_deform+=("$(field deforming <<<"$out")")
  fcl_check+=("$(check_of <<<"$out")")
  fcl_small+=("$(field "small every pair" <<<"$out")"); fcl_first+=("$(field "small first contact" <<<"$out")")
  echo "round $r, FCL alone:         small ${fcl_small[-1]} / ${fcl_first[-1]} ms, rigid ${fcl_rigid[-1]} ms, deforming ${fcl_deform[-1]} ms (check ${fcl_check[-1]})"
  out=$(LD_PRELOAD="$SHIM" KDET_FCL_INTERPOSE_STATS=1 "$APP" bench "$CHECKS" 2>"$BUILD/interpose_bench.err")
  kdet_rigid+=("$(field rigid <<<"$out")"); kdet_deform+=("$(field deforming <<<"$out")")
  kdet_check+=("$(check_of <<<"$out")")
  kdet_small+=("$(field "small every pair" <<<"$out")"); kdet_first+=("$(field "small first contact" <<<"$out")")
  echo "round $r, under the library: small ${kdet_small[-1]} / ${kdet_first[-1]} ms, rigid ${kdet_rigid[-1]} ms, deforming ${kdet_deform[-1]} ms (check ${kdet_check[-1]})"
  grep -q "fell back to FCL 0" "$BUILD/interpose_bench.err" ||
    { echo "interpose_bench: kDet refused a pair:" >&2; cat "$BUILD/interpose_bench.err" >&2; exit 1; }
done
tail -n1 "$BUILD/interpose_bench.err"
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
fr=$(median "${fcl_rigid[@]}"); kr=$(median "${kdet_rigid[@]}")
fd=$(median "${fcl_deform[@]}"); kd=$(median "${kdet_deform[@]}")
fc=$(median "${fcl_check[@]}"); kc=$(median "${kdet_check[@]}")
fs=$(median "${fcl_small[@]}"); ks=$(median "${kdet_small[@]}")
ff=$(median "${fcl_first[@]}"); kf=$(median "${kdet_first[@]}")
awk -v fr="$fr" -v kr="$kr" -v fd="$fd" -v kd="$kd" -v fc="$fc" -v kc="$kc" \
    -v fs="$fs" -v ks="$ks" -v ff="$ff" -v kf="$kf" 'BEGIN {
  printf "medians over the rounds: small meshes, every pair %.4f ms alone, %.4f ms under the library (%.2fx)\n", fs, ks, fs / ks
  printf "                         small meshes, first contact %.4f ms alone, %.4f ms under the library (%.2fx)\n", ff, kf, ff / kf
  printf "                         rigid check %.3f ms alone, %.3f ms under the library (%.2fx)\n", fr, kr, fr / kr
  printf "                         deforming frame %.3f ms alone, %.3f ms under the library (%.2fx; FCL'\''s refit in both)\n", fd, kd, fd / kd
  printf "                         of it the check after the update %.3f ms alone, %.3f ms under the library (%.2fx)\n", fc, kc, fc / kc }'
