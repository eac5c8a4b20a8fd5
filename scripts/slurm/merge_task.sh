#!/usr/bin/env bash
# The merge job of city3d-slurm: every shard folder of WORK into OUTPUT.
# Arguments: CITY3D WORK N OUTPUT
set -euo pipefail
city3d="$1" work="$2" shards="$3" output="$4"
folders=()
for ((k = 1; k <= shards; k++)); do folders+=("$work/shard-$k"); done
exec "$city3d" merge "${folders[@]}" -o "$output"
