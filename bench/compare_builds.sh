#!/usr/bin/env bash
# Are two builds' outputs byte-identical? For a change that must not change any output (a refactoring,
# an optimisation: issues 26 and 27). Runs both binaries on the Delft block (both LAS tiles, 160
# footprints, every default output plus --gpkg --3dtiles --cityjsonseq; and from both LAZ tiles in 14
# cropping passes, --group-area 0 --block-size 60, with -j 1 and -j 2) and on every single-building
# cloud of city3d_dev, city3d_dev_large and City3D's building instances, then compares every output
# file byte for byte; report.csv and report.json (parsed) up to their timings (cpu_seconds, seconds),
# and report.html up to each building's seconds: the page as text, its embedded data parsed (the
# JSON's layout is not compared). Prints each difference and exits 1 if there is one.
#
# Usage: bench/compare_builds.sh OLD_CITY3D NEW_CITY3D [SETS]   (SETS: comma-separated of delft, delft_laz,
#        dev, dev_large, instances; default all). Work files in $TMPDIR (or /tmp). Needs bash, python3, cmp.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
[[ $# -ge 2 ]] || { sed -n '2,12p' "$0" >&2; exit 2; }
old="$(realpath "$1")"
new="$(realpath "$2")"
sets="${3:-delft,delft_laz,dev,dev_large,instances}"
shared="$here/../../shared/data"
work="$(mktemp -d "${TMPDIR:-/tmp}/city3d_compare.XXXXXX")"
trap 'rm -rf "$work"' EXIT

clouds() {  # the clouds of a manifest, one per line
  python3 -c 'import csv, os, sys
d = sys.argv[1]
for row in csv.DictReader(open(os.path.join(d, "manifest.csv"))): print(os.path.join(d, row["ply"]))' "$1"
}

differences=0
compare() {  # compare NAME DIR_OLD DIR_NEW
  local name="$1" a="$2" b="$3" f
  while IFS= read -r f; do
    if [[ ! -f "$b/$f" ]]; then
      echo "$name: $f only in the old build's output"; differences=$((differences + 1)); continue
    fi
    case "$f" in
      report.csv | report.json | report.html | run.json | resume.journal) continue ;;
    esac
    cmp -s "$a/$f" "$b/$f" || { echo "$name: $f differs"; differences=$((differences + 1)); }
  done < <(cd "$a" && find . -type f | sed 's|^\./||' | sort)
  while IFS= read -r f; do
    [[ -f "$a/$f" ]] || { echo "$name: $f only in the new build's output"; differences=$((differences + 1)); }
  done < <(cd "$b" && find . -type f | sed 's|^\./||' | sort)
  # The reports up to their timings.
  python3 - "$a" "$b" "$name" <<'EOF' || differences=$((differences + 1))
import csv, json, sys
a, b, name = sys.argv[1:4]
def rows(d):
    with open(d + "/report.csv") as f:
        return [{k: v for k, v in r.items() if k not in ("cpu_seconds", "seconds")} for r in csv.DictReader(f)]
def summary(d):
    j = json.load(open(d + "/report.json"))
    j.get("summary", {}).pop("seconds", None)
    for r in j.get("buildings", []):
        r.pop("cpu_seconds", None), r.pop("seconds", None)
    return j
def page(d):  # the page's text around its data, and the data without each building's seconds
    text = open(d + "/report.html").read()
    begin = text.index('<script id="data" type="application/json">')
    begin = text.index(">", begin) + 1
    end = text.index("</script>", begin)
    data = json.loads(text[begin:end])
    for r in data.get("buildings", []):
        r.pop("t", None)
    return text[:begin] + text[end:], data
bad = [what for what, f in (("report.csv", rows), ("report.json", summary), ("report.html", page)) if f(a) != f(b)]
for what in bad:
    print(f"{name}: {what} differs (up to its timings)")
sys.exit(1 if bad else 0)
EOF
  echo "$name: compared $(cd "$a" && find . -type f | wc -l) files"
}

run_both() {  # run_both NAME ARGS...
  local name="$1"; shift
  "$old" reconstruct "$@" --no-progress -q --no-resume -o "$work/$name.old"
  "$new" reconstruct "$@" --no-progress -q --no-resume -o "$work/$name.new"
  compare "$name" "$work/$name.old" "$work/$name.new"
}

IFS=, read -r -a wanted <<< "$sets"
for s in "${wanted[@]}"; do
  case "$s" in
    delft)
      d="$shared/ahn3_delft"
      run_both delft "$d/ahn3_cropped_1.las" "$d/ahn3_cropped_2.las" -f "$d/footprints/bgt_pand_laz_area.gpkg" \
        --id-field gml_id --gpkg --3dtiles --cityjsonseq -j 2 ;;
    delft_laz)  # the LAZ tiles in 14 cropping passes: later passes decode only the chunks they need
      d="$shared/ahn3_delft"
      for j in 1 2; do
        run_both "delft_laz_j$j" "$d/ahn3_cropped_1.laz" "$d/ahn3_cropped_2.laz" -f "$d/footprints/bgt_pand_laz_area.gpkg" \
          --id-field gml_id --group-area 0 --block-size 60 -j "$j"
      done ;;
    dev) mapfile -t c < <(clouds "$shared/city3d_dev"); run_both dev "${c[@]}" -j 2 ;;
    dev_large) mapfile -t c < <(clouds "$shared/city3d_dev_large"); run_both dev_large "${c[@]}" -j 2 ;;
    instances) run_both instances "$shared/city3d_repo/building_instances" -j 2 ;;
    *) echo "compare_builds.sh: unknown set '$s' (delft, delft_laz, dev, dev_large, instances)" >&2; exit 2 ;;
  esac
done
if [[ $differences -gt 0 ]]; then
  echo "$differences difference(s)"
  exit 1
fi
echo "byte-identical: ${sets}"
