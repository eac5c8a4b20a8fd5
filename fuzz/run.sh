#!/usr/bin/env bash
# Builds the libFuzzer harnesses (clang, ASan + UBSan) and runs each for SECONDS, at most JOBS at a
# time, each on its own corpus folder plus the seeds (tests/data and fuzz/seeds). A crash, leak,
# timeout (one input over 60 s of wall time: the runs are niced on a shared machine) or out-of-memory is written to fuzz/regressions/<harness>/, which
# ctest replays in the normal build, and makes this script exit 1.
#   fuzz/run.sh SECONDS [JOBS] [HARNESS...]     e.g. fuzz/run.sh 10 2        (CI: a short run of each)
# Per harness it prints one line: runs, coverage (edges), features, corpus size, exec/s, peak RSS.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:?usage: fuzz/run.sh SECONDS [JOBS] [HARNESS...]}"
jobs="${2:-2}"
shift $(( $# >= 2 ? 2 : 1 ))
all=(las laz ply obj_footprints ogr_footprints config journal)
harnesses=("$@")
[ ${#harnesses[@]} -gt 0 ] || harnesses=("${all[@]}")

build="${FUZZ_BUILD:-build-fuzz}"  # FUZZ_BUILD: another build folder (long runs beside development)
if [ ! -f "$build/CMakeCache.txt" ]; then
  CXX=clang++ cmake -S fuzz -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCITY3D_MAIN_BUILD="$PWD/build" >/dev/null
fi
cmake --build "$build" -j "$jobs" >/dev/null

# Seeds of each harness: small valid and broken files from tests/data, and fuzz/seeds/<harness>.
seeds_of() {
  case "$1" in
    las) echo tests/data/las tests/data/las/broken ;;
    laz) echo fuzz/seeds/laz ;;
    ply) echo tests/data/ply tests/data/ply/broken ;;
    obj_footprints) echo tests/data/footprints ;;
    ogr_footprints) echo tests/data/footprints fuzz/seeds/ogr_footprints ;;
    *) [ -d "fuzz/seeds/$1" ] && echo "fuzz/seeds/$1" ;;
  esac
}

run_one() {
  local h="$1" corpus="$build/corpus/$1" artifacts="fuzz/regressions/$1/" log="$build/logs/$1.log"
  mkdir -p "$corpus" "$artifacts" "$build/logs"
  # (|| keeps set -e from ending this background function before the failure is printed)
  local status=0
  # shellcheck disable=SC2046
  nice -n 19 "$build/fuzz_$h" -max_total_time="$seconds" -timeout="${FUZZ_TIMEOUT:-60}" -rss_limit_mb=2048 -max_len=65536 \
    -print_final_stats=1 -artifact_prefix="$artifacts" "$corpus" $(seeds_of "$h") >"$log" 2>&1 || status=$?
  local done_line runs eps rss
  done_line=$(grep -E '^#[0-9]+[[:space:]]+DONE' "$log" | tail -1 || true)
  runs=$(grep -oE 'number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' || echo "?")
  eps=$(grep -oE 'average_exec_per_sec: *[0-9]+' "$log" | grep -oE '[0-9]+$' || echo "?")
  rss=$(grep -oE 'peak_rss_mb: *[0-9]+' "$log" | grep -oE '[0-9]+$' || echo "?")
  local cov ft corp
  cov=$(echo "$done_line" | grep -oE 'cov: [0-9]+' | grep -oE '[0-9]+' || echo "?")
  ft=$(echo "$done_line" | grep -oE 'ft: [0-9]+' | grep -oE '[0-9]+' || echo "?")
  corp=$(echo "$done_line" | grep -oE 'corp: [0-9]+' | grep -oE '[0-9]+' || echo "?")
  if [ $status -eq 0 ]; then
    printf 'fuzz %-15s ok     %ss: runs %s, cov %s, ft %s, corpus %s, %s exec/s, peak %s MB\n' \
      "$h" "$seconds" "$runs" "$cov" "$ft" "$corp" "$eps" "$rss"
  else
    printf 'fuzz %-15s FAILED (exit %s) after %s runs: see %s and %s\n' "$h" "$status" "$runs" "$log" "$artifacts"
    grep -E 'ERROR|SUMMARY' "$log" | head -5 || true
  fi
  return $status
}

failed=0
pids=()
for h in "${harnesses[@]}"; do
  [ -x "$build/fuzz_$h" ] || { echo "fuzz $h: no harness built, skipped"; continue; }
  run_one "$h" & pids+=($!)
  if [ ${#pids[@]} -ge "$jobs" ]; then
    wait "${pids[0]}" || failed=1
    pids=("${pids[@]:1}")
  fi
done
for p in "${pids[@]}"; do wait "$p" || failed=1; done
exit $failed
