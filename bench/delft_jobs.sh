#!/usr/bin/env bash
# Issue 11: the Delft block (both LAS tiles, 160 footprints) with -j 1 and -j 2, one run after the
# other, RUNS times alternating: wall time, CPU time (user + sys of city3d and its solver processes)
# and peak memory of each run, their medians, the -j 2 / -j 1 wall ratio, and whether the two
# outputs are byte-identical. Usage: bench/delft_jobs.sh [CITY3D_BINARY] [RUNS]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${1:-$here/../build/city3d}"
runs="${2:-5}"
data="$here/../../shared/data/ahn3_delft"
[[ -x "$bin" ]] || { echo "delft_jobs.sh: no city3d binary at $bin" >&2; exit 2; }
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
declare -A wall cpu mem
for ((i = 1; i <= runs; i++)); do
  for j in 1 2; do
    rm -rf "$out/j$j"
    /usr/bin/time -f "%e %U %S %M" -o "$out/time" "$bin" reconstruct "$data/ahn3_cropped_1.las" \
      "$data/ahn3_cropped_2.las" --footprints "$data/footprints/bgt_pand_laz_area.gpkg" --id-field gml_id \
      -j "$j" --no-progress -q --no-resume --output "$out/j$j"
    read -r w u s kb < "$out/time"
    c=$(awk -v u="$u" -v s="$s" 'BEGIN { printf "%.2f", u + s }')
    echo "run $i -j $j: ${w} s wall, ${c} s CPU, $((kb / 1024)) MB peak"
    wall[$j]+="$w "; cpu[$j]+="$c "; mem[$j]+="$kb "
  done
  cmp -s "$out/j1/buildings.city.json" "$out/j2/buildings.city.json" || { echo "run $i: -j 1 and -j 2 differ" >&2; exit 1; }
done
for j in 1 2; do
  mw=$(tr ' ' '\n' <<< "${wall[$j]}" | grep . | median)
  mc=$(tr ' ' '\n' <<< "${cpu[$j]}" | grep . | median)
  mm=$(tr ' ' '\n' <<< "${mem[$j]}" | grep . | median | cut -d. -f1)
  echo "median of $runs runs, -j $j: $mw s wall, $mc s CPU, $((mm / 1024)) MB peak"
  eval "w$j=$mw"
done
awk -v a="$w1" -v b="$w2" 'BEGIN { printf "-j 2 wall / -j 1 wall: %.2f\n", b / a }'
echo "outputs of -j 1 and -j 2: byte-identical in every run"
