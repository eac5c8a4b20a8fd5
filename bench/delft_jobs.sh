#!/usr/bin/env bash
# Issue 11: the Delft block (both LAS tiles, 160 footprints) with -j 1 and -j 2, one run after the
# other, RUNS times alternating: wall time, CPU time (user + sys of city3d and its solver processes)
# and peak memory of each run, their medians, the -j 2 / -j 1 wall ratio (of the medians, and the median
# of each run's pair: the two runs of a pair are back to back, so a machine whose speed drifts between
# pairs moves both alike), the -j 2 / -j 1 CPU ratio (near 1 when the second core was free), and whether
# the two outputs are byte-identical. With SET=dev the same for the 200 single-building clouds of
# ../shared/data/city3d_dev (without CityJSON; the models are compared).
# Usage: bench/delft_jobs.sh [CITY3D_BINARY] [RUNS] [SET=delft|dev]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${1:-$here/../build/city3d}"
runs="${2:-5}"
set_name="${3:-delft}"
data="$here/../../shared/data/ahn3_delft"
[[ -x "$bin" ]] || { echo "delft_jobs.sh: no city3d binary at $bin" >&2; exit 2; }
case "$set_name" in
  delft) inputs=("$data/ahn3_cropped_1.las" "$data/ahn3_cropped_2.las"
                 --footprints "$data/footprints/bgt_pand_laz_area.gpkg" --id-field gml_id)
         compared=buildings.city.json ;;
  dev) dev="$here/../../shared/data/city3d_dev"
       mapfile -t inputs < <(python3 -c "import csv, sys; [print(sys.argv[1] + '/' + r['ply'])
for r in csv.DictReader(open(sys.argv[1] + '/manifest.csv'))]" "$dev")
       inputs+=(--no-cityjson)
       compared=models ;;
  *) echo "delft_jobs.sh: SET is delft or dev, not $set_name" >&2; exit 2 ;;
esac
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
declare -A wall cpu mem
pairs=""
for ((i = 1; i <= runs; i++)); do
  for j in 1 2; do
    rm -rf "$out/j$j"
    python3 "$here/timed.py" -o "$out/time" "$bin" reconstruct "${inputs[@]}" \
      -j "$j" --no-progress -q --no-resume --output "$out/j$j"
    read -r w u s kb < "$out/time"
    c=$(awk -v u="$u" -v s="$s" 'BEGIN { printf "%.2f", u + s }')
    echo "run $i -j $j: ${w} s wall, ${c} s CPU, $((kb / 1024)) MB peak"
    wall[$j]+="$w "; cpu[$j]+="$c "; mem[$j]+="$kb "
    [[ $j == 1 ]] && w_one=$w
  done
  diff -rq "$out/j1/$compared" "$out/j2/$compared" > /dev/null || { echo "run $i: -j 1 and -j 2 differ" >&2; exit 1; }
  pairs+="$(awk -v a="$w_one" -v b="$w" 'BEGIN { printf "%.4f", b / a }') "
done
for j in 1 2; do
  mw=$(tr ' ' '\n' <<< "${wall[$j]}" | grep . | median)
  mc=$(tr ' ' '\n' <<< "${cpu[$j]}" | grep . | median)
  mm=$(tr ' ' '\n' <<< "${mem[$j]}" | grep . | median | cut -d. -f1)
  echo "median of $runs runs, -j $j: $mw s wall, $mc s CPU, $((mm / 1024)) MB peak"
  eval "w$j=$mw c$j=$mc"
done
awk -v a="$w1" -v b="$w2" 'BEGIN { printf "-j 2 wall / -j 1 wall: %.2f\n", b / a }'
# The same work on two threads should cost the same CPU: well above 1, the two threads slowed each other
# down (or a neighbour on the host took part of the cores), which a serial stage of city3d does not do.
awk -v a="$c1" -v b="$c2" 'BEGIN { printf "-j 2 CPU / -j 1 CPU: %.2f\n", b / a }'
echo "-j 2 wall / -j 1 wall, median of the $runs pairs' ratios: $(tr ' ' '\n' <<< "$pairs" | grep . | median | awk '{ printf "%.2f", $1 }')"
echo "outputs of -j 1 and -j 2: byte-identical in every run"
