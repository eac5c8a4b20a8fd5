#!/usr/bin/env python3
"""An AHN3-sized tile from the Delft block (issue 12): the two AHN3 tiles of ../shared/data/ahn3_delft
replicated in a grid (default 6 x 5 copies: 25.5 M points, 4,800 footprints), the footprints shifted
with their copy and their ids made unique; then `city3d reconstruct` on it and on the Delft block
itself, timed by bench/timed.py. Prints what the issue asks: points, footprints, wall and CPU time, peak
memory, seconds per million points of both, and their ratio.

    python3 bench/synthetic_tile.py --city3d build/city3d [--grid 6x5] [--jobs 2] [--runs 1] [--work build/synthetic_tile]
    python3 bench/synthetic_tile.py --outputs "--gpkg --3dtiles"   # issue 25: what these outputs add
    python3 bench/synthetic_tile.py --city3d NEW/city3d --baseline OLD/city3d --runs 3   # side by side
    python3 bench/synthetic_tile.py --laz ...   # the tile as LAZ (bench/synthetic_laz.py), the same footprints

With --outputs, each run also reconstructs the tile with those options (side by side, in alternation with
the run without them) and the summary gives the peak memory and time they add. With --baseline OTHER_BINARY,
each run also times that build on the same inputs, in alternation, and the summary gives the ratios.

Nothing is deleted between the timed runs: each run writes to a folder of its own, and the folders (and any left
from an earlier invocation, moved aside first) are deleted at the end. On ext4, creating a file searches past every
inode freed in the last minutes (a file per building: 4,800 after deleting the previous run's 4,800 cost 2-4 s of
CPU against 0.2 s on a file system with no recent deletions; docs/BENCHMARKS.md, "twelfth step"), a cost of the
benchmark's own clean-up, not of the run it times.

The generated tile (about 0.7 GB of LAS) goes to --work (build/ by default), never into git. Needs
python3 and ogr2ogr (gdal-bin) only.
"""
import argparse
import array
import os
import shutil
import struct
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
# The copies' spacing (300 m by 250 m) is synthetic_laz.py's, so that the LAZ tile's points and these
# footprints are moved alike.
from synthetic_laz import STEP_X, STEP_Y, make_laz  # noqa: E402  (bench/synthetic_laz.py)
from timed import run_timed  # noqa: E402  (bench/timed.py)

DELFT = os.path.join(HERE, "..", "..", "shared", "data", "ahn3_delft")
TILES = [os.path.join(DELFT, "ahn3_cropped_1.las"), os.path.join(DELFT, "ahn3_cropped_2.las")]
FOOTPRINTS = os.path.join(DELFT, "footprints", "bgt_pand_laz_area.gpkg")


def read_las(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] != b"LASF":
        sys.exit(f"{path}: not a LAS file")
    offset = struct.unpack_from("<I", data, 96)[0]
    fmt, length = struct.unpack_from("<BH", data, 104)
    count = struct.unpack_from("<I", data, 107)[0]
    by_return = struct.unpack_from("<5I", data, 111)
    scale = struct.unpack_from("<3d", data, 131)
    origin = struct.unpack_from("<3d", data, 155)
    bounds = struct.unpack_from("<6d", data, 179)  # max x, min x, max y, min y, max z, min z
    if fmt != 1 or length != 28:
        sys.exit(f"{path}: expected point format 1 (28-byte records), got {fmt} ({length} bytes)")
    points = data[offset:offset + count * length]
    return dict(header=data[:offset], count=count, by_return=by_return, scale=scale, origin=origin,
                bounds=bounds, points=points)


def make_tile(work, nx, ny):
    tiles = [read_las(p) for p in TILES]
    if any(t["scale"] != tiles[0]["scale"] or t["origin"] != tiles[0]["origin"] for t in tiles):
        sys.exit("the Delft tiles have different scales or offsets")
    scale = tiles[0]["scale"]
    dx_raw, dy_raw = round(STEP_X / scale[0]), round(STEP_Y / scale[1])
    las = os.path.join(work, "tile.las")
    total = sum(t["count"] for t in tiles) * nx * ny
    if total >= 2**32:
        sys.exit("too many points for a LAS 1.2 header")
    header = bytearray(tiles[0]["header"])
    struct.pack_into("<I", header, 107, total)
    struct.pack_into("<5I", header, 111, *[sum(t["by_return"][i] for t in tiles) * nx * ny for i in range(5)])
    max_x = max(t["bounds"][0] for t in tiles) + (nx - 1) * STEP_X
    min_x = min(t["bounds"][1] for t in tiles)
    max_y = max(t["bounds"][2] for t in tiles) + (ny - 1) * STEP_Y
    min_y = min(t["bounds"][3] for t in tiles)
    max_z = max(t["bounds"][4] for t in tiles)
    min_z = min(t["bounds"][5] for t in tiles)
    struct.pack_into("<6d", header, 179, max_x, min_x, max_y, min_y, max_z, min_z)
    # Each 28-byte record is 7 little-endian 32-bit words; X and Y are words 0 and 1.
    words = []
    for t in tiles:
        a = array.array("i")
        a.frombytes(t["points"])
        if sys.byteorder != "little":
            a.byteswap()
        words.append(a)
    with open(las, "wb") as out:
        out.write(header)
        for row in range(ny):
            for col in range(nx):
                for a in words:
                    b = array.array("i", a)
                    b[0::7] = array.array("i", (v + col * dx_raw for v in a[0::7]))
                    b[1::7] = array.array("i", (v + row * dy_raw for v in a[1::7]))
                    if sys.byteorder != "little":
                        b.byteswap()
                    out.write(b.tobytes())
    gpkg = os.path.join(work, "footprints.gpkg")
    for row in range(ny):
        for col in range(nx):
            sql = (f"SELECT ST_Translate(GEOMETRY, {col * STEP_X}, {row * STEP_Y}, 0) AS geom, "
                   f"gml_id || '_r{row}c{col}' AS gml_id FROM buildingpart")
            subprocess.run(["ogr2ogr", "-f", "GPKG", gpkg, FOOTPRINTS, "-dialect", "SQLite", "-sql", sql,
                            "-nln", "buildingpart"] + (["-append"] if row or col else []), check=True)
    return las, gpkg, total, 160 * nx * ny


def timed(command):
    """(wall s, CPU s, peak RSS MB) of a command (bench/timed.py)."""
    wall, user, system, kb = run_timed(command)
    return wall, user + system, kb / 1024


def median(values):
    v = sorted(values)
    return v[len(v) // 2] if len(v) % 2 else (v[len(v) // 2 - 1] + v[len(v) // 2]) / 2


def report_counts(folder):
    with open(os.path.join(folder, "report.csv")) as f:
        rows = f.read().splitlines()[1:]
    status = [r.split(",")[1] for r in rows]
    return {s: status.count(s) for s in ("ok", "fallback", "skipped", "failed")}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--city3d", default=os.path.join(HERE, "..", "build", "city3d"))
    p.add_argument("--grid", default="6x5", help="copies in x and y (default 6x5: 25.5 M points)")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--runs", type=int, default=1, help="runs of each, medians reported")
    p.add_argument("--work", default=os.path.join(HERE, "..", "build", "synthetic_tile"))
    p.add_argument("--keep", action="store_true", help="keep the generated tile and every run's outputs")
    p.add_argument("--outputs", default="", help="options of more outputs (\"--gpkg --3dtiles\"): the tile is also "
                   "reconstructed with them, and what they add to peak memory and time is printed")
    p.add_argument("--baseline", default="", help="another city3d binary, timed in alternation on the same inputs")
    p.add_argument("--laz", action="store_true", help="the tile as LAZ (bench/synthetic_laz.py: the full chunks of "
                   "both tiles, 24.0 M points in 480 chunks) instead of LAS")
    a = p.parse_args()
    nx, ny = (int(v) for v in a.grid.lower().split("x"))
    os.makedirs(a.work, exist_ok=True)
    # Outputs of an earlier invocation are moved aside (a rename frees no inode) and deleted after the timing.
    trash = os.path.join(a.work, f"trash-{os.getpid()}")
    for entry in sorted(os.listdir(a.work)):
        if entry.startswith("out_"):
            os.makedirs(trash, exist_ok=True)
            os.rename(os.path.join(a.work, entry), os.path.join(trash, entry))
    las, gpkg, points, footprints = make_tile(a.work, nx, ny)
    if a.laz:
        las = os.path.join(a.work, "tile.laz")
        points, _ = make_laz(las, nx, ny)
    print(f"synthetic tile: {points:,} points, {footprints:,} footprints ({nx} x {ny} copies of the Delft block), "
          f"{os.path.getsize(las) / 2**20:.0f} MB {'LAZ' if a.laz else 'LAS'}")
    delft_points = sum(read_las(t)["count"] for t in TILES)
    jobs = ["--id-field", "gml_id", "-j", str(a.jobs), "--no-progress", "-q", "--no-resume"]
    builds = [("", a.city3d)] + ([("baseline ", a.baseline)] if a.baseline else [])
    runs = [("delft", TILES + ["-f", FOOTPRINTS]), ("tile", [las, "-f", gpkg])]
    if a.outputs:
        runs.append(("tile+", [las, "-f", gpkg] + a.outputs.split()))
    results = {label + name: [] for label, _ in builds for name, _ in runs}
    written = []
    for run in range(a.runs):
        for label, binary in builds:
            for name, cmd in runs:
                out = os.path.join(a.work, f"out_{label.strip() or 'city3d'}_{name}_{run + 1}")
                written.append(out)
                r = timed([binary, "reconstruct"] + cmd + jobs + ["-o", out])
                results[label + name].append(r)
                print(f"run {run + 1} {label}{name}: {r[0]:.1f} s wall, {r[1]:.1f} s CPU, {r[2]:.0f} MB peak; "
                      f"{report_counts(out)}", flush=True)
    print()
    for label, _ in builds:
        for name, n, fp in (("delft", delft_points, 160), ("tile", points, footprints)):
            rs = results[label + name]
            wall, cpu, rss = (median([r[k] for r in rs]) for k in range(3))
            print(f"{label}{name:5s}: {n / 1e6:.2f} M points, {fp} footprints, -j {a.jobs}: wall {wall:.1f} s, "
                  f"CPU {cpu:.1f} s, peak RSS {rss:.0f} MB; {wall / (n / 1e6):.2f} s wall and {cpu / (n / 1e6):.2f} s "
                  f"CPU per M points, {cpu / fp * 1000:.0f} ms CPU per footprint")
        ratio = ((median([r[0] for r in results[label + "tile"]]) / points) /
                 (median([r[0] for r in results[label + "delft"]]) / delft_points))
        print(f"{label}tile / Delft block, wall time per M points: {ratio:.2f}")
    if a.baseline:
        for name in ("delft", "tile"):
            new, old = results[name], results["baseline " + name]
            print(f"{name} against the baseline (medians of the runs' ratios): wall "
                  f"{median([n[0] / o[0] for n, o in zip(new, old)]):.3f}, CPU "
                  f"{median([n[1] / o[1] for n, o in zip(new, old)]):.3f}, peak RSS "
                  f"{median([n[2] / o[2] for n, o in zip(new, old)]):.3f}")
    if a.outputs:
        plain, more = results["tile"], results["tile+"]
        print(f"tile with {a.outputs}: wall {median([r[0] for r in more]):.1f} s, CPU {median([r[1] for r in more]):.1f} s, "
              f"peak RSS {median([r[2] for r in more]):.0f} MB; they add "
              f"{median([m[0] - t[0] for t, m in zip(plain, more)]):+.1f} s wall, "
              f"{median([m[1] - t[1] for t, m in zip(plain, more)]):+.1f} s CPU, peak RSS x"
              f"{median([m[2] / t[2] for t, m in zip(plain, more)]):.3f} (medians of the runs' differences)")
    shutil.rmtree(trash, ignore_errors=True)
    if a.keep:
        return
    for out in written:
        shutil.rmtree(out, ignore_errors=True)
    shutil.rmtree(a.work, ignore_errors=True)

if __name__ == "__main__":
    main()
