#!/usr/bin/env bash
# Long fuzzing runs (issue 14): every harness for an hour (or SECONDS), two at a time (FUZZ_JOBS), niced, with
# the figures docs/BENCHMARKS.md records (runs, coverage, exec/s, peak RSS). Crashes, leaks and
# hangs land in fuzz/regressions/<harness>/ (replayed by ctest) and make the script exit 1.
#   bench/fuzz.sh [SECONDS] [HARNESS...]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-3600}"
shift $(( $# >= 1 ? 1 : 0 ))
echo "fuzz: ${seconds} s per harness, ${FUZZ_JOBS:-2} at a time, nice 19, on $(nproc) cores; load $(cut -d' ' -f1-3 /proc/loadavg)"
exec fuzz/run.sh "$seconds" "${FUZZ_JOBS:-2}" "$@"
