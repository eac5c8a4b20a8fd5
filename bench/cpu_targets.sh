#!/usr/bin/env bash
# Issue 27's figures in one run, each as a median (run it on a quiet machine; the figures and the
# commands behind them are in docs/BENCHMARKS.md, "CPU: issue 27"):
#  1. the Delft block (both LAS tiles, 160 footprints, every default output), -j 1 and -j 2 in
#     alternation: wall, CPU and peak memory, and the -j 2 / -j 1 wall and CPU ratios
#     (bench/delft_jobs.sh);
#  2. city3d_dev and city3d_dev_large (-j 1): the per-building CPU, total, median, p99 and maximum,
#     with the stage profile (bench/stage_profile.py), and city3d_dev's -j 2 / -j 1 wall ratio;
#  3. LAZ decoding through the LAS reader on 1 and 2 threads (bench_laz_decode): both AHN3 tiles (13
#     and 5 chunks, which cap two threads at 1.88x and 1.92x) and a file of 480 chunks made from them
#     (bench/synthetic_laz.py, 24 M points, 127 MB, deleted afterwards);
#  4. with --tile only (it writes 0.7 GB and takes minutes): the 25.5 M-point synthetic tile, -j 2
#     (bench/synthetic_tile.py).
# The issue's targets were set on a slower machine than later ones: for ratios to its baseline build,
# measured side by side, see bench/cpu_against.py.
# Usage: bench/cpu_targets.sh [--tile] [BUILD_DIR=build] [RUNS=5]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
tile=0
if [[ "${1:-}" == "--tile" ]]; then tile=1; shift; fi
build="$(realpath "${1:-$here/../build}")"
runs="${2:-5}"
bin="$build/city3d"
data="$here/../../shared/data"
[[ -x "$bin" ]] || { echo "cpu_targets.sh: no city3d binary at $bin" >&2; exit 2; }

echo "== 1. Delft block, -j 1 and -j 2, $runs runs each"
bash "$here/delft_jobs.sh" "$bin" "$runs" | grep -E '^median|wall /|CPU /|byte-identical'

echo "== 2. city3d_dev and city3d_dev_large, -j 1: per-building CPU; city3d_dev -j 1 and -j 2"
python3 "$here/stage_profile.py" --city3d "$bin" --sets dev,dev_large --runs 1 | grep -E '^#|^per-building|^\| (all|selection|planes|polylines|measure) '
bash "$here/delft_jobs.sh" "$bin" 1 dev | grep -E '^median|wall /|CPU /|byte-identical'

echo "== 3. LAZ decoding through the LAS reader, 1 and 2 threads, median of 11"
cmake --build "$build" --target bench_laz_decode -j2 > /dev/null
many="$(mktemp -d)"
trap 'rm -rf "$many"' EXIT
python3 "$here/synthetic_laz.py" "$many/tile.laz"
for f in "$data/ahn3_delft/ahn3_cropped_1.laz" "$data/ahn3_delft/ahn3_cropped_2.laz" "$many/tile.laz"; do
  "$build/bench/bench_laz_decode" "$f" 11 1,2 | tail -n 1
done
rm -rf "$many"

if ((tile)); then
  echo "== 4. the synthetic tile (6 x 5 copies of the Delft block), -j 2"
  python3 "$here/synthetic_tile.py" --city3d "$bin" --jobs 2 --runs 1 --work "$build/synthetic_tile"
fi
