#!/usr/bin/env bash
# Runs bench_las_read several times (it builds nothing) and prints the median of the per-run medians.
# Usage: bench/las_read.sh [BENCH_BINARY] [FILE] [RUNS] [REPEATS_PER_RUN]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${1:-$here/../build/bench/bench_las_read}"
file="${2:-$here/../../shared/data/ahn3_delft/ahn3_cropped_1.las}"
runs="${3:-5}"
repeats="${4:-5}"
[[ -x "$bin" ]] || { echo "las_read.sh: no bench binary at $bin (build target bench_las_read first)" >&2; exit 2; }
[[ -f "$file" ]] || { echo "las_read.sh: no input file $file" >&2; exit 2; }

medians=()
for ((i = 1; i <= runs; i++)); do
  m="$("$bin" "$file" "$repeats" | awk '/^median:/ {print $2}')"
  echo "run $i: $m Mpoints/s"
  medians+=("$m")
done
printf '%s\n' "${medians[@]}" | sort -g | awk -v f="$file" '
  { v[NR] = $1 }
  END { m = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
        printf "median of %d runs: %.1f Mpoints/s (xyz + classification, %s)\n", NR, m, f }'
