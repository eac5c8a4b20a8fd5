#!/usr/bin/env bash
# The whole job on the AHN3 Delft block (issue 5): both LAS (or LAZ) tiles, 160 BGT footprints, read +
# crop + reconstruct + write with -j 2. Prints wall time and peak memory (bench/timed.py) of each run and the
# medians. Usage: bench/delft_block.sh [CITY3D_BINARY] [RUNS] [EXT=las|laz]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${1:-$here/../build/city3d}"
runs="${2:-5}"
ext="${3:-las}"
data="$here/../../shared/data/ahn3_delft"
[[ -x "$bin" ]] || { echo "delft_block.sh: no city3d binary at $bin" >&2; exit 2; }
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT

walls=()
mems=()
for ((i = 1; i <= runs; i++)); do
  rm -rf "$out/run"
  python3 "$here/timed.py" -o "$out/time" "$bin" reconstruct "$data/ahn3_cropped_1.$ext" "$data/ahn3_cropped_2.$ext" \
    --footprints "$data/footprints/bgt_pand_laz_area.gpkg" --id-field gml_id -j 2 --no-progress -q \
    --output "$out/run"
  read -r wall _ _ kb < "$out/time"
  summary="$(awk -F, 'NR > 1 {n[$2]++; f += $15} END {printf "%d ok, %d fallback, %d skipped, %d failed, %d faces", n["ok"], n["fallback"], n["skipped"], n["failed"], f}' "$out/run/report.csv")"
  echo "run $i: ${wall} s, $((kb / 1024)) MB peak; $summary"
  walls+=("$wall")
  mems+=("$kb")
done
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
echo "median of $runs runs: $(printf '%s\n' "${walls[@]}" | median) s wall, $(( $(printf '%s\n' "${mems[@]}" | median | cut -d. -f1) / 1024 )) MB peak"
