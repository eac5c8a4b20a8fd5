#!/usr/bin/env python3
"""Issues 10 and 23 acceptance benchmark: city3d against roofer (3DBAG's production tool) on the Delft block.

Runs `city3d reconstruct` on the two AHN3 tiles with the 160 BGT footprints, evaluates every model with
`city3d evaluate` on the same class-6 points roofer's models were measured on
(../shared/data/ahn3_delft/reference_roofer/points/<gml_id>.ply, 76,818 points), and prints the per-building
table side by side with roofer's (reference_roofer/per_building.tsv) and a summary for both tools: median,
mean and pooled RMSE (pooled: over all points together), faces, points farther than 1 m from the model,
buildings where city3d is closer, validity, and city3d's CPU time (user + sys of the child process).
Both directions are measured: points to model (RMSE, points farther than 1 m) and model to points (issue 23:
surface more than 1 m above the highest point within 1.5 m in plan, `city3d evaluate`'s unsupported_area,
and how far each model's highest vertex lies above its building's highest point), for both tools with this
build's evaluator.

Usage: bench/delft_vs_roofer.py [--city3d build/city3d] [--jobs 2] [--out DIR] [--roofer-eval]
                                [--points DIR] [--quiet] [-- extra city3d options]
--roofer-eval takes roofer's RMSE and points farther than 1 m from this build's evaluator too, instead of from
per_building.tsv (they agree to 0.1 mm). --points DIR evaluates both tools against other points (one
<gml_id>.ply per building; bench/thinned_delft.py makes thinned tiles and evaluates against the full points).
--tiles A B runs city3d on other tiles than the two LAS tiles (e.g. thinned ones).
Python 3 standard library only.
"""
import argparse
import csv
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
DELFT = os.path.normpath(os.path.join(HERE, "..", "..", "shared", "data", "ahn3_delft"))
REF = os.path.join(DELFT, "reference_roofer")
FAR = 1.0  # metres: a point farther than this from its model is "unexplained"


def evaluate(city3d, model, points, residuals):
    """RMSE, faces, validity, squared-distance sum, point count and points farther than FAR."""
    text = subprocess.run([city3d, "evaluate", model, points, "--residuals", residuals], check=True,
                          capture_output=True, text=True).stdout
    fields = dict(line.split(": ", 1) for line in text.splitlines() if ": " in line)
    sq, n, far = 0.0, 0, 0
    with open(residuals) as f:
        for row in csv.DictReader(f):
            d = float(row["distance"])
            sq += d * d
            n += 1
            far += d > FAR
    os.remove(residuals)
    return {"rmse": float(fields["rmse"]), "faces": int(fields["faces"]), "valid": fields["valid"] == "yes",
            "sq": sq, "n": n, "far": far, "unsupported": float(fields["unsupported_area"].split()[0]),
            "unsupported_roof": float(fields["unsupported_roof_area"].split()[0]),
            "excess": float(fields["height_excess"]), "above": float(fields["highest_vertex_above_points"])}


def run_city3d(city3d, out, jobs, extra, tiles):
    cmd = [city3d, "reconstruct", *tiles,
           "-f", os.path.join(DELFT, "footprints", "bgt_pand_laz_area.gpkg"), "--id-field", "gml_id",
           "-j", str(jobs), "--no-progress", "-q", "--no-resume", "--no-html", "-o", out, *extra]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.monotonic()
    subprocess.run(cmd, check=True)
    wall = time.monotonic() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    with open(os.path.join(out, "report.csv")) as f:
        report = {row["id"]: row for row in csv.DictReader(f)}
    return cmd, report, cpu, wall, after.ru_maxrss


def summary(label, rows, key):
    rs = [r[key] for r in rows]
    n = sum(r["n"] for r in rs)
    pooled = math.sqrt(sum(r["sq"] for r in rs) / n)
    if all(r["far"] >= 0 for r in rs):
        far = sum(r["far"] for r in rs)
        over5 = sum(r["far"] > 0.05 * r["n"] for r in rs)
        far_text = f"{far:,} ({100 * far / n:.2f}%) | {over5}"
    else:  # roofer's figures from per_building.tsv: no residuals
        far_text = "- | -"
    return (f"| {label} | {statistics.median(r['rmse'] for r in rs):.3f} | {statistics.mean(r['rmse'] for r in rs):.3f} | "
            f"{pooled:.3f} | {sum(r['faces'] for r in rs):,} | {far_text} | {sum(r['valid'] for r in rs)} |")


def support_summary(label, rows, key):
    """Model to points (issue 23): unsupported surface and highest vertices above the building's points."""
    rs = [r[key] for r in rows if r[key]["n"] > 0]
    area = sum(r["unsupported"] for r in rs)
    roof = sum(r["unsupported_roof"] for r in rs)
    return (f"| {label} | {area:.1f} ({roof:.1f} on roofs) | {sum(r['unsupported'] > 1 for r in rs)} / {sum(r['unsupported'] > 10 for r in rs)} | "
            f"{sum(r['above'] > 1 for r in rs)} / {sum(r['above'] > 3 for r in rs)} | "
            f"{max((r['excess'] for r in rs), default=0):.1f} |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--city3d", default=os.path.join(HERE, "..", "build", "city3d"))
    ap.add_argument("--evaluator", default=None,
                    help="the city3d that evaluates the models (default --city3d): another build's models measured "
                         "with this build's evaluate")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default=None)
    ap.add_argument("--roofer-eval", action="store_true")
    ap.add_argument("--quiet", action="store_true", help="summary only, no per-building table")
    ap.add_argument("--points", default=os.path.join(REF, "points"), help="evaluation points, <gml_id>.ply each")
    ap.add_argument("--tiles", nargs="+", default=[os.path.join(DELFT, "ahn3_cropped_1.las"),
                                                   os.path.join(DELFT, "ahn3_cropped_2.las")])
    ap.add_argument("extra", nargs="*", help="more city3d options, after --")
    args = ap.parse_args()
    out = args.out or tempfile.mkdtemp(prefix="city3d_delft_")
    city3d = os.path.abspath(args.city3d)
    evaluator = os.path.abspath(args.evaluator or args.city3d)

    with open(os.path.join(REF, "per_building.tsv")) as f:
        reference = list(csv.DictReader(f, delimiter="\t"))
    cmd, report, cpu, wall, rss = run_city3d(city3d, out, args.jobs, args.extra, [os.path.abspath(t) for t in args.tiles])

    rows = []
    for ref in reference:
        bid = ref["id"]
        points = os.path.join(args.points, bid + ".ply")
        model = os.path.join(out, "models", bid + ".obj")
        row = {"id": bid, "level": report.get(bid, {}).get("level", "none"),
               "unexplained": report.get(bid, {}).get("unexplained_points", "")}
        if os.path.exists(model):
            row["city3d"] = evaluate(evaluator, model, points, os.path.join(out, bid + ".residuals.csv"))
        else:
            row["city3d"] = {"rmse": float("nan"), "faces": 0, "valid": False, "sq": 0.0, "n": 0, "far": 0,
                             "unsupported": 0.0, "unsupported_roof": 0.0, "excess": 0.0, "above": 0.0}
        # roofer's model to points with this build's evaluator always; its RMSE from per_building.tsv unless
        # --roofer-eval (they agree to 0.1 mm).
        row["roofer"] = evaluate(evaluator, os.path.join(REF, "lod22", bid + ".obj"), points,
                                 os.path.join(out, bid + ".roofer_residuals.csv"))
        if not args.roofer_eval and args.points == os.path.join(REF, "points"):
            n = int(ref["points"])
            r = float(ref["roofer_lod22_rmse"])
            row["roofer"].update({"rmse": r, "faces": int(ref["roofer_lod22_faces"]), "sq": r * r * n, "n": n,
                                  "far": -1})
        rows.append(row)

    with open(os.path.join(out, "delft_vs_roofer.tsv"), "w") as f:
        f.write("id\tpoints\troofer_rmse\troofer_faces\tcity3d_rmse\tcity3d_faces\tcity3d_far_1m\tcity3d_level\t"
                "roofer_unsupported_m2\troofer_excess\tcity3d_unsupported_m2\tcity3d_excess\tcity3d_above_points\n")
        for r in rows:
            c, o = r["city3d"], r["roofer"]
            f.write(f"{r['id']}\t{c['n']}\t{o['rmse']:.4f}\t{o['faces']}\t"
                    f"{c['rmse']:.4f}\t{c['faces']}\t{c['far']}\t{r['level']}\t"
                    f"{o['unsupported']:.2f}\t{o['excess']:.3f}\t{c['unsupported']:.2f}\t{c['excess']:.3f}\t{c['above']:.3f}\n")

    if not args.quiet:
        print("| building | points | roofer RMSE | roofer faces | city3d RMSE | city3d faces | city3d > 1 m | better |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- |")
        for r in sorted(rows, key=lambda r: r["city3d"]["rmse"] - r["roofer"]["rmse"]):
            c, o = r["city3d"], r["roofer"]
            better = "city3d" if c["rmse"] < o["rmse"] else "roofer" if o["rmse"] < c["rmse"] else "="
            print(f"| {r['id']} | {c['n']} | {o['rmse']:.4f} | {o['faces']} | {c['rmse']:.4f} | {c['faces']} | "
                  f"{c['far']} | {better} |")
        print()

    print("command: " + " ".join(os.path.relpath(a) if os.path.isabs(a) and os.path.exists(a) else a for a in cmd))
    print(f"city3d: CPU {cpu:.2f} s (user + sys), wall {wall:.2f} s, peak RSS {rss / 1024:.0f} MB, -j {args.jobs}")
    levels = {}
    for r in rows:
        levels[r["level"]] = levels.get(r["level"], 0) + 1
    print("levels: " + ", ".join(f"{k} {v}" for k, v in sorted(levels.items())))
    better = sum(r["city3d"]["rmse"] < r["roofer"]["rmse"] for r in rows)
    print(f"buildings where city3d is closer to the points than roofer: {better} of {len(rows)}")
    print()
    print("| models (160 buildings) | median RMSE | mean RMSE | pooled RMSE | faces | points > 1 m | buildings > 5% "
          "of points > 1 m | valid |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    print(summary("roofer LoD2.2", rows, "roofer"))
    print(summary("city3d", rows, "city3d"))
    print()
    print("| model to points (160 buildings) | unsupported area (m2) | buildings > 1 m2 / > 10 m2 | "
          "highest vertex > 1 m / > 3 m above the highest point | worst height excess (m) |")
    print("| --- | --- | --- | --- | --- |")
    print(support_summary("roofer LoD2.2", rows, "roofer"))
    print(support_summary("city3d", rows, "city3d"))
    above = [r["id"] for r in rows if r["city3d"]["above"] > 1 and r["roofer"]["above"] <= 1]
    print(f"city3d models whose highest vertex is more than 1 m above their points where roofer's is not: {len(above)}"
          + (" (" + ", ".join(a[:9] for a in above) + ")" if above else ""))
    worst = sorted(rows, key=lambda r: -r["city3d"]["unsupported"])[:8]
    print("most unsupported city3d models: " + ", ".join(f"{r['id'][:9]} {r['city3d']['unsupported']:.1f} m2 "
                                                         f"({r['city3d']['excess']:.1f} m)" for r in worst
                                                         if r["city3d"]["unsupported"] > 0))
    print(f"\nper-building rows: {os.path.join(out, 'delft_vs_roofer.tsv')}")


if __name__ == "__main__":
    sys.exit(main())
