#!/usr/bin/env bash
# The k-free study (kDet paper Section 6.1, Figure 6): `kdet analyze` over every mesh the project
# can reach (../shared/data/** and the suite's procedural scenes, written by
# `kdet_bench --export-scenes`), then per-mesh rows, a summary binned by triangle count and
# Tukey box plots of k per bin (gnuplot).
#
#   benchmarks/kfree_study.sh [BUILD_DIR] [OUT_DIR] [--quick]
#
# BUILD_DIR holds kdet and benchmarks/kdet_bench (default: build); OUT_DIR gets kfree.csv,
# kfree.txt, kfree_summary.md, kfree_binned.dat, kfree_boxplot.gp and kfree_boxplot.png
# (default: benchmarks/results/kfree). --quick exports only the small procedural scenes.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(dirname "$here")
build=$root/build
out=$here/results/kfree
quick=()
pos=0
for a in "$@"; do
  case "$a" in
    --quick) quick=(--quick) ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) if [ $pos -eq 0 ]; then build=$a; else out=$a; fi; pos=$((pos + 1)) ;;
  esac
done
kdet=$build/kdet
bench=$build/benchmarks/kdet_bench
for exe in "$kdet" "$bench"; do
  [ -x "$exe" ] || { echo "kfree_study.sh: $exe not found (build the kdet and kdet_bench targets)" >&2; exit 2; }
done
data=$(cd "$root/.." && pwd)/shared/data
mkdir -p "$out"
out=$(cd "$out" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

echo "kfree_study: exporting the procedural scenes" >&2
"$bench" --export-scenes "$tmp/procedural" "${quick[@]}"

roots=("$tmp/procedural")
[ -d "$data" ] && roots+=("$data") || echo "kfree_study: $data missing: procedural meshes only" >&2
mapfile -t files < <(find -L "${roots[@]}" -type f \( -iname '*.ply' -o -iname '*.obj' -o -iname '*.off' \
                      -o -iname '*.stl' \) | sort)
echo "kfree_study: analysing ${#files[@]} meshes" >&2
"$kdet" analyze "${files[@]}" --csv "$tmp/kfree.csv" --threads 2 > "$tmp/kfree.txt"
# Paths of the temporary folder mean nothing later: keep the names relative to their root.
sed -e "s|$tmp/procedural/|procedural/|g" -e "s|$data/|shared/data/|g" "$tmp/kfree.csv" > "$out/kfree.csv"
sed -e "s|$tmp/procedural/|procedural/|g" -e "s|$data/|shared/data/|g" "$tmp/kfree.txt" > "$out/kfree.txt"

# Bins by triangle count (as the paper's Figure 6 bins by polygon count).
awk -F, 'NR > 1 {
  t = $2; b = (t < 1000) ? 1 : (t < 10000) ? 2 : (t < 100000) ? 3 : (t < 1000000) ? 4 : 5;
  split("<1k 1k-10k 10k-100k 100k-1M >=1M", L, " ");
  src = ($1 ~ /^shared\/data\//) ? "shared-data" : ($1 ~ /chazelle|coplanar|huge-ratio|soup_/) ? "adversarial" : "procedural";
  printf "%d %s %s %s %s %s %s %s\n", b, L[b], $3, $4, $8, $9, $1, src
}' "$out/kfree.csv" | sort -n -k1,1 > "$out/kfree_binned.dat"

# summarize FILTER LABEL: one table row over the rows of kfree_binned.dat that FILTER (awk) selects.
summarize() {
  awk "$1" "$out/kfree_binned.dat" | sort -g -k3,3 | awk -v lab="$2" '{
      n++; k[n] = $3; sk += $3; sk2 += $3 * $3; sm += $4; sa += $5; sh += $6; if ($6 > mh) mh = $6;
      if ($3 > mk) mk = $3 }
    END {
      if (n == 0) exit;
      med = (n % 2) ? k[(n + 1) / 2] : (k[n / 2] + k[n / 2 + 1]) / 2;
      m = sk / n; sd = sqrt(sk2 / n - m * m);
      printf "| %s | %d | %.1f (%.1f) | %g | %d | %.2f | %.2f | %.1f (%d) |\n", lab, n, m, sd, med, mk, sm / n, sa / n, sh / n, mh
    }'
}
{
  echo "| meshes | count | k: mean (sd) | k: median | k: max | neighbours per triangle: mean | adjacent share: mean | height: mean (max) |"
  echo "| --- | ---: | --- | ---: | ---: | ---: | ---: | --- |"
  summarize '$1 == 1' '<1k triangles'
  summarize '$1 == 2' '1k-10k'
  summarize '$1 == 3' '10k-100k'
  summarize '$1 == 4' '100k-1M'
  summarize '$1 == 5' '>=1M'
  summarize '$8 == "shared-data"' 'source: ../shared/data'
  summarize '$8 == "procedural"' 'source: procedural scenes'
  summarize '$8 == "adversarial"' 'source: adversarial (Chazelle, coplanar, size ratio, soups)'
  summarize '1' 'all'
} > "$out/kfree_summary.md"

cat > "$out/kfree_boxplot.gp" <<'GP'
set terminal pngcairo size 1100,500 noenhanced
set output 'kfree_boxplot.png'
set multiplot layout 1,2 title 'k-free study (Definition 3.1): Tukey box plots binned by triangle count'
set style data boxplot
set style boxplot outliers pointtype 7
set style fill solid 0.3 border -1
set boxwidth 0.5
set pointsize 0.5
set xlabel 'triangles'
set grid y
unset key
set logscale y
set ylabel 'minimum k (max neighbour count + 1)'
plot 'kfree_binned.dat' using (1.0):3:(0.5):2
unset logscale y
set ylabel 'mean neighbour count per triangle'
plot 'kfree_binned.dat' using (1.0):4:(0.5):2
unset multiplot
GP
if command -v gnuplot > /dev/null; then
  (cd "$out" && gnuplot kfree_boxplot.gp) || echo "kfree_study: gnuplot failed" >&2
else
  echo "kfree_study: gnuplot not installed: no PNG" >&2
fi
cat "$out/kfree_summary.md"
echo "kfree_study: wrote $out/{kfree.csv,kfree.txt,kfree_summary.md,kfree_boxplot.png}" >&2
