#!/usr/bin/env bash
# Decode speed of the LAZ decoder on the files laz-perf was timed on (reference figures:
# shared/data/laz/README.md, "Decode speed of laz-perf 3.4.0"). Quote the CPU-time median.
# Usage: bench/laz_decode.sh [build-dir=build] [repeats=21]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
repeats="${2:-21}"
data="$root/../shared/data"
cmake --build "$build" --target bench_laz_decode -j2 >/dev/null
for file in \
  "$data/laz/cases/las12_pf3_autzen_trim_3chunks.laz" \
  "$data/ahn3_delft/ahn3_cropped_1.laz" \
  "$data/ahn3_delft/ahn3_cropped_2.laz" \
  "$data/laz/cases/las14_pf7_autzen_60k_2chunks.laz"; do
  "$build/bench/bench_laz_decode" "$file" "$repeats" | tail -n 1
done
