#!/usr/bin/env bash
# One array task of city3d-slurm: shards (task - 1) * M + 1 .. task * M of N, one after the other, each
# into WORK/shard-K. A shard that was killed resumes from its journal; one that had finished only
# re-assembles its outputs. Exits non-zero when any shard failed, so the merge job does not start.
# Arguments: CITY3D WORK N M RECONSTRUCT_ARGUMENTS...
set -uo pipefail
city3d="$1" work="$2" shards="$3" per_task="$4"
shift 4
task="${SLURM_ARRAY_TASK_ID:?not run as a Slurm array task}"
first=$(( (task - 1) * per_task + 1 ))
last=$(( task * per_task < shards ? task * per_task : shards ))
status=0
for ((k = first; k <= last; k++)); do
  echo "city3d-slurm: shard $k/$shards on $(hostname) at $(date -u +%FT%TZ)"
  # -j first, so that a -j among the arguments wins.
  "$city3d" reconstruct -j "${SLURM_CPUS_PER_TASK:-1}" "$@" --shard "$k/$shards" --no-progress -o "$work/shard-$k" ||
    status=$?
done
exit "$status"
