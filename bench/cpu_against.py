#!/usr/bin/env python3
"""Issue 27's CPU figures as ratios to a baseline build, measured side by side.

Machines differ (the baseline of issue 27 took 3.6 s of CPU on the Delft block where the targets were
set and 2.6 s on a later machine), so a figure means something only next to the baseline's on the same
machine in the same minutes. This runs two builds in alternation, RUNS rounds, and prints for each set
the medians of both and their ratio:
  - delft: the Delft block (both LAS tiles, 160 footprints, every default output) at -j 1: the process's
    CPU (user + sys, its solver processes included) and its peak memory;
  - dev, dev_large: the single-building clouds of ../shared/data/city3d_dev and city3d_dev_large at -j 1:
    the per-building CPU summed over the set (report.csv's cpu_seconds), and its p99 and maximum;
and the two dev sets together. The issue's targets as ratios to the baseline of its table are printed
beside them (Delft block: 1.6 s of the 3.68 s the baseline took there; the dev sets: half).

    python3 bench/cpu_against.py --baseline OLD_CITY3D [--city3d build/city3d] [--runs 3]
                                 [--sets delft,dev,dev_large]

Needs python3 only. A build of the baseline: `git worktree add /tmp/base d0ce34a` (issue 27's), then
`cmake -S /tmp/base -B /tmp/base/build -DCMAKE_BUILD_TYPE=Release && cmake --build /tmp/base/build
--target city3d`.
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from stage_profile import clouds_of, percentile  # noqa: E402  (bench/stage_profile.py)
from timed import run_timed  # noqa: E402  (bench/timed.py)

SHARED = os.path.normpath(os.path.join(HERE, "..", "..", "shared", "data"))
DELFT = os.path.join(SHARED, "ahn3_delft")
TARGETS = {"delft": 1.6 / 3.68, "dev": 0.5, "dev_large": 0.5, "dev sets together": 0.5}


def run(city3d, args, out):
    """(CPU seconds of the process and its children, peak RSS in MB, per-building CPU list)."""
    cmd = [city3d, "reconstruct", *args, "--no-progress", "-q", "--no-resume", "-o", out]
    with tempfile.TemporaryFile() as stderr:
        try:
            _, user, system, kb = run_timed(cmd, stdout=subprocess.DEVNULL, stderr=stderr)
        except subprocess.CalledProcessError:
            stderr.seek(0)
            sys.exit("cpu_against.py: failed: " + " ".join(cmd) + "\n" + stderr.read().decode(errors="replace"))
    with open(os.path.join(out, "report.csv")) as f:
        buildings = [float(row["cpu_seconds"]) for row in csv.DictReader(f) if row["cpu_seconds"]]
    return user + system, kb / 1024.0, buildings


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--baseline", required=True, help="the baseline's city3d binary")
    p.add_argument("--city3d", default=os.path.join(HERE, "..", "build", "city3d"))
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--sets", default="delft,dev,dev_large")
    a = p.parse_args()
    builds = {"baseline": os.path.abspath(a.baseline), "new": os.path.abspath(a.city3d)}
    for name, path in builds.items():
        if not os.access(path, os.X_OK):
            sys.exit(f"cpu_against.py: no {name} binary at {path}")
    if a.runs < 1:
        sys.exit("cpu_against.py: --runs must be at least 1")
    arguments = {
        "delft": [os.path.join(DELFT, "ahn3_cropped_1.las"), os.path.join(DELFT, "ahn3_cropped_2.las"), "-f",
                  os.path.join(DELFT, "footprints", "bgt_pand_laz_area.gpkg"), "--id-field", "gml_id", "-j", "1"],
        "dev": clouds_of(os.path.join(SHARED, "city3d_dev")) + ["-j", "1", "--no-cityjson"],
        "dev_large": clouds_of(os.path.join(SHARED, "city3d_dev_large")) + ["-j", "1", "--no-cityjson"],
    }
    sets = a.sets.split(",")
    for s in sets:
        if s not in arguments:
            sys.exit(f"cpu_against.py: unknown set {s} (delft, dev, dev_large)")

    print(f"baseline: {builds['baseline']}\nnew:      {builds['new']}\n{a.runs} rounds, the builds in alternation\n")
    print("| figure | baseline | new | new / baseline | target |")
    print("| --- | --- | --- | --- | --- |")
    totals = {"baseline": 0.0, "new": 0.0}
    with tempfile.TemporaryDirectory() as work:
        for s in sets:
            results = {name: [] for name in builds}
            for k in range(a.runs):
                for name, path in builds.items():
                    results[name].append(run(path, arguments[s], os.path.join(work, f"{s}_{name}_{k}")))
            target = f"{TARGETS[s]:.2f}"
            if s == "delft":
                cpu = {n: statistics.median(r[0] for r in results[n]) for n in builds}
                peak = {n: statistics.median(r[1] for r in results[n]) for n in builds}
                print(f"| Delft block -j 1: CPU, median of {a.runs} | {cpu['baseline']:.2f} s | {cpu['new']:.2f} s | "
                      f"{cpu['new'] / cpu['baseline']:.2f} | {target} |")
                print(f"| Delft block -j 1: peak RSS | {peak['baseline']:.0f} MB | {peak['new']:.0f} MB | "
                      f"{peak['new'] / peak['baseline']:.2f} | 1.00 or less |")
                continue
            total = {n: statistics.median(sum(r[2]) for r in results[n]) for n in builds}
            # The tail from the round of least total (the least disturbed).
            tail = {}
            for n in builds:
                least = min((r[2] for r in results[n]), key=sum)
                tail[n] = f"p99 {percentile(least, 99):.2f} s, max {max(least):.2f} s"
            print(f"| {s}: per-building CPU, median of {a.runs} | {total['baseline']:.2f} s ({tail['baseline']}) | "
                  f"{total['new']:.2f} s ({tail['new']}) | {total['new'] / total['baseline']:.2f} | {target} |")
            for n in builds:
                totals[n] += total[n]
    if "dev" in sets and "dev_large" in sets:
        print(f"| dev sets together | {totals['baseline']:.2f} s | {totals['new']:.2f} s | "
              f"{totals['new'] / totals['baseline']:.2f} | {TARGETS['dev sets together']:.2f} |")


if __name__ == "__main__":
    main()
