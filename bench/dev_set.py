#!/usr/bin/env python3
"""Issue 4 acceptance benchmark: reconstruct every building of ../shared/data/city3d_dev (200 clouds,
with City3D's own model beside each) and city3d_repo/building_instances (100 clouds), then compare
with the same evaluation code (`city3d evaluate`): share of models, validity, LoD2 share, RMSE and
face counts against City3D's models, per dataset, and time per building.

Usage: bench/dev_set.py [--city3d build/city3d] [--jobs 2] [--runs 1] [--out DIR] [--city3d-floors]
       [-- extra city3d options]
--city3d-floors puts our floors where City3D's reference models have theirs (AHN3 z = 0, Vaihingen 265,
DALES 1.05; ../shared/data/README.md) instead of at each cloud's lowest point.
Times are the per-building seconds of the report (one building on one core); with --runs N the
per-building median over N runs is used.
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


FLOORS = {"AHN3": "0", "Vaihingen": "265", "Dales3d": "1.05"}


def reconstruct(city3d, clouds, out, jobs, extra):
    cmd = [city3d, "reconstruct", *clouds, "-j", str(jobs), "--no-progress", "-q", "--no-resume",
           "--no-cityjson", "-o", out, *extra]
    subprocess.run(cmd, check=True)
    with open(os.path.join(out, "report.csv")) as f:
        return {row["id"]: row for row in csv.DictReader(f)}


def evaluate(city3d, model, points):
    text = subprocess.run([city3d, "evaluate", model, points], check=True, capture_output=True, text=True).stdout
    fields = dict(line.split(": ", 1) for line in text.splitlines() if ": " in line)
    return float(fields["rmse"]), int(fields["faces"])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--city3d", default=os.path.join(HERE, "..", "build", "city3d"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--out", default=None)
    ap.add_argument("--city3d-floors", action="store_true")
    ap.add_argument("extra", nargs="*", help="more city3d options, after --")
    args = ap.parse_args()
    out = args.out or tempfile.mkdtemp(prefix="city3d_dev_")

    dev = os.path.join(SHARED, "city3d_dev")
    with open(os.path.join(dev, "manifest.csv")) as f:
        manifest = list(csv.DictReader(f))
    instances = os.path.join(SHARED, "city3d_repo", "building_instances")
    sets = {}
    for row in manifest:
        sets.setdefault(row["dataset"], []).append(os.path.join(dev, row["ply"]))
    sets["instances"] = sorted(os.path.join(instances, n) for n in os.listdir(instances) if n.endswith(".ply"))

    rows = []
    for name, clouds in sets.items():
        seconds = {}
        report = None
        for run in range(args.runs):
            extra = list(args.extra)
            if args.city3d_floors and name in FLOORS:
                extra += ["--ground-z", FLOORS[name]]
            report = reconstruct(args.city3d, clouds, os.path.join(out, name), args.jobs, extra)
            for bid, r in report.items():
                seconds.setdefault(bid, []).append(float(r["seconds"]))
        for cloud in clouds:
            bid = os.path.splitext(os.path.basename(cloud))[0]
            r = report[bid]
            ref = os.path.splitext(cloud)[0] + ".obj"
            ref_rmse, ref_faces = evaluate(args.city3d, ref, cloud) if os.path.exists(ref) else (None, None)
            rows.append({
                "set": name, "id": bid, "status": r["status"], "level": r["level"], "valid": r["valid"] == "1",
                "rmse": float(r["rmse"]) if r["rmse"] else None, "faces": int(r["faces"]),
                "ref_rmse": ref_rmse, "ref_faces": ref_faces, "seconds": statistics.median(seconds[bid]),
                "reason": r["reason"]})

    with open(os.path.join(out, "dev_set.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)

    def summary(label, rs):
        n = len(rs)
        models = sum(r["rmse"] is not None for r in rs)
        valid = sum(r["valid"] for r in rs)
        lod2 = sum(r["level"] == "LoD2.2" for r in rs)  # full LoD2, not the footprint-walls fallback
        rm = [r["rmse"] for r in rs if r["rmse"] is not None]
        ref = [r for r in rs if r["ref_rmse"] is not None]
        secs = [r["seconds"] for r in rs]
        line = (f"| {label} | {n} | {100 * models / n:.0f}% | {100 * valid / n:.0f}% | {100 * lod2 / n:.1f}% | "
                f"{statistics.median(rm):.3f} | ")
        if ref:
            line += (f"{statistics.median(r['ref_rmse'] for r in ref):.3f} | {statistics.median(r['faces'] for r in ref):.0f} | "
                     f"{statistics.median(r['ref_faces'] for r in ref):.0f} | ")
        else:
            line += "- | " + f"{statistics.median(r['faces'] for r in rs):.0f} | - | "
        line += f"{statistics.median(secs):.3f} | {max(secs):.2f} |"
        print(line)

    print("| set | buildings | models | valid | full LoD2 | median RMSE (m) | City3D median RMSE (m) | median faces | "
          "City3D median faces | median s | max s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name in sets:
        summary(name, [r for r in rows if r["set"] == name])
    summary("all dev (AHN3+Vaihingen+DALES)", [r for r in rows if r["set"] != "instances"])
    summary("all 300", rows)
    print(f"\nper-building rows: {os.path.join(out, 'dev_set.csv')}")


if __name__ == "__main__":
    sys.exit(main())
