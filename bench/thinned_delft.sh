#!/usr/bin/env bash
# Issue 23: the Delft block at lower point densities. Keeps every 2nd, 4th and 8th point record of the two
# AHN3 tiles (bench/thin_las.py; every 4th is about 2 points per m2, as in older or non-Dutch surveys),
# reconstructs the block from each, and evaluates every model against the full-density points of its
# building (bench/delft_vs_roofer.py: both ways, points to model and model to points; roofer's models are
# those of the full-density tiles). Prints per density the levels reached and the two summary tables.
#
# Usage: bench/thinned_delft.sh [CITY3D [EVALUATOR]]   (default build/city3d for both; EVALUATOR measures
#        another build's models with this build's evaluate). Work files in $TMPDIR (or /tmp).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
city3d="$(realpath "${1:-$here/../build/city3d}")"
evaluator="$(realpath "${2:-$city3d}")"
delft="$here/../../shared/data/ahn3_delft"
work="$(mktemp -d "${TMPDIR:-/tmp}/city3d_thinned.XXXXXX")"
trap 'rm -rf "$work"' EXIT
for k in 1 2 4 8; do
  tiles=()
  for t in 1 2; do
    if [ "$k" = 1 ]; then
      tiles+=("$delft/ahn3_cropped_$t.las")
    else
      python3 "$here/thin_las.py" "$delft/ahn3_cropped_$t.las" "$work/tile${t}_every$k.las" "$k" >/dev/null
      tiles+=("$work/tile${t}_every$k.las")
    fi
  done
  case "$k" in 1) label="every point record (full density)" ;; 2) label="every 2nd point record" ;;
    *) label="every ${k}th point record" ;; esac
  echo "## $label"
  python3 "$here/delft_vs_roofer.py" --quiet --city3d "$city3d" --evaluator "$evaluator" --out "$work/out$k" \
    --tiles "${tiles[@]}" | grep -E '^(levels|\|)' | grep -v -- '---'
  echo
done
