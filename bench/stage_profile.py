#!/usr/bin/env python3
"""Issue 27: where the CPU goes, stage by stage. Runs `city3d reconstruct --profile` on the Delft block
(both LAS tiles, 160 footprints, -j 1, every default output) and on the single-building clouds of
../shared/data/city3d_dev and city3d_dev_large (-j 1), and prints per stage the CPU seconds of the first
models and of the rebuilds, summed over each set's buildings (medians over --runs runs), with the share of
each stage; then, from the reports, the per-building CPU (report.csv's cpu_seconds): total, median, p99 and
maximum.

    python3 bench/stage_profile.py [--city3d build/city3d] [--runs 3] [--sets delft,dev,dev_large]

Needs python3 only. Stage CPU is thread CPU plus the solver processes' (CBC), counted exclusive: a stage
nested in another is taken out of it (include/city3d/stage_profile.hpp). Every set runs on one thread:
a building's CPU is then its own, not inflated by a second thread on the same core's caches (the clouds
ran one at a time whatever -j said until the threads shared them; bench/delft_jobs.sh measures -j 2).
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.normpath(os.path.join(HERE, "..", "..", "shared", "data"))
DELFT = os.path.join(SHARED, "ahn3_delft")


def clouds_of(folder):
    with open(os.path.join(folder, "manifest.csv")) as f:
        return [os.path.join(folder, row["ply"]) for row in csv.DictReader(f)]


def run(city3d, args, out):
    """The profile lines of one run (stage -> (first, rebuilds)) and the report's per-building CPU."""
    cmd = [city3d, "reconstruct", *args, "--profile", "--no-progress", "-q", "--no-resume", "-o", out]
    result = subprocess.run(cmd, check=True, capture_output=True, text=True)
    stages = {}
    for line in result.stderr.splitlines():
        parts = line.split()
        if len(parts) == 6 and parts[0] == "profile:" and parts[1] not in ("stage", "all"):
            stages[parts[1]] = (float(parts[2]), float(parts[3]))
    if not stages:
        sys.exit("stage_profile.py: no profile in the output of: " + " ".join(cmd) + "\n" + result.stderr)
    with open(os.path.join(out, "report.csv")) as f:
        cpu = [float(row["cpu_seconds"]) for row in csv.DictReader(f) if row["cpu_seconds"]]
    return stages, cpu


def percentile(values, p):
    v = sorted(values)
    if not v:
        return float("nan")
    k = (len(v) - 1) * p / 100.0
    lo = int(k)
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (v[hi] - v[lo]) * (k - lo)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--city3d", default=os.path.join(HERE, "..", "build", "city3d"))
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--sets", default="delft,dev,dev_large", help="comma-separated: delft, dev, dev_large")
    a = p.parse_args()
    city3d = os.path.abspath(a.city3d)
    sets = {}
    wanted = a.sets.split(",")
    if "delft" in wanted:
        sets["Delft block (-j 1)"] = [os.path.join(DELFT, "ahn3_cropped_1.las"), os.path.join(DELFT, "ahn3_cropped_2.las"),
                                      "-f", os.path.join(DELFT, "footprints", "bgt_pand_laz_area.gpkg"),
                                      "--id-field", "gml_id", "-j", "1"]
    if "dev" in wanted:
        sets["city3d_dev (-j 1)"] = clouds_of(os.path.join(SHARED, "city3d_dev")) + ["-j", "1", "--no-cityjson"]
    if "dev_large" in wanted:
        sets["city3d_dev_large (-j 1)"] = clouds_of(os.path.join(SHARED, "city3d_dev_large")) + ["-j", "1",
                                                                                            "--no-cityjson"]
    with tempfile.TemporaryDirectory() as work:
        for name, args in sets.items():
            runs = [run(city3d, args, os.path.join(work, f"run{k}")) for k in range(a.runs)]
            stages = list(runs[0][0].keys())
            first = {s: statistics.median(r[0][s][0] for r in runs) for s in stages}
            rebuild = {s: statistics.median(r[0][s][1] for r in runs) for s in stages}
            total = sum(first.values()) + sum(rebuild.values())
            print(f"## {name}: stage CPU, median of {a.runs} runs")
            print("| stage | first model (s) | rebuilds (s) | total (s) | share |")
            print("| --- | --- | --- | --- | --- |")
            for s in sorted(stages, key=lambda s: -(first[s] + rebuild[s])):
                both = first[s] + rebuild[s]
                print(f"| {s} | {first[s]:.3f} | {rebuild[s]:.3f} | {both:.3f} | {100 * both / total:.1f}% |")
            print(f"| all | {sum(first.values()):.3f} | {sum(rebuild.values()):.3f} | {total:.3f} | 100% |")
            cpu = min((r[1] for r in runs), key=sum)  # the run of least total: the least disturbed
            print(f"per-building CPU ({len(cpu)} buildings, the run of least total): total {sum(cpu):.2f} s, "
                  f"median {statistics.median(cpu) * 1000:.1f} ms, p99 {percentile(cpu, 99):.3f} s, "
                  f"max {max(cpu):.3f} s")
            print()


if __name__ == "__main__":
    main()
