#!/usr/bin/env python3
"""Inputs with the mistakes users make, on real points: each made from the Delft data and run by every build
given, so that a change can show what each build does with them. Prints one row per case and build: the exit
code, the statuses, and the figures that tell a right answer from a wrong one.

  - unclassified tile:  Delft's tile 2 with its building class (6) made 1, beside tile 1 as it is: fid 95
                        (b1105d28c) lies on both; its ridge (h_ridge) is 14.3 m with both tiles classified.
  - withheld copies:    the sample's tile 1 with each building point doubled 3 m higher, flagged withheld.
  - ground +50 m:       the sample's tiles with their ground points 50 m higher (another height datum).
  - ground class 0:     --ground-class 0 (the tiles' ground is class 2): every floor at a roof's lowest point.
  - ignore classes:     --ignore-classes on the sample (the ground then comes from the points around).
  - GeoJSON without crs: the sample's footprints as RFC 7946 GeoJSON (WGS 84 by the standard), in RD metres.
  - count halved:       the sample's tile 1 with its header's point count halved.
  - noise floor:        one building's points as a single-building LAS with one noise point (class 7) 30 m below.

    python3 bench/input_mistakes.py [--city3d build/city3d] [--baseline OTHER/city3d]

Needs python3 only (the LAS files are rewritten with struct).
"""
import argparse
import csv
import json
import os
import struct
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
DELFT = os.path.normpath(os.path.join(HERE, "..", "..", "shared", "data", "ahn3_delft"))
SAMPLE = os.path.normpath(os.path.join(HERE, "..", "data"))
SAMPLE_TILES = [os.path.join(SAMPLE, "delft_sample_1.las"), os.path.join(SAMPLE, "delft_sample_2.las")]
SAMPLE_FOOTPRINTS = os.path.join(SAMPLE, "delft_sample_footprints.gpkg")


def read_las(path):
    """(header bytes, point offset, record length, records as bytearrays) of a LAS 1.2 file."""
    data = open(path, "rb").read()
    offset = struct.unpack_from("<I", data, 96)[0]
    length = struct.unpack_from("<H", data, 105)[0]
    count = struct.unpack_from("<I", data, 107)[0]
    records = [bytearray(data[offset + i * length: offset + (i + 1) * length]) for i in range(count)]
    return bytearray(data[:offset]), records


def write_las(path, header, records, count=None):
    header = bytearray(header)
    struct.pack_into("<I", header, 107, len(records) if count is None else count)
    scale = struct.unpack_from("<3d", header, 131)
    offset = struct.unpack_from("<3d", header, 155)
    lo = [min(struct.unpack_from("<i", r, 4 * a)[0] for r in records) * scale[a] + offset[a] for a in range(3)]
    hi = [max(struct.unpack_from("<i", r, 4 * a)[0] for r in records) * scale[a] + offset[a] for a in range(3)]
    for a in range(3):
        struct.pack_into("<2d", header, 179 + 16 * a, hi[a], lo[a])
    with open(path, "wb") as f:
        f.write(header)
        for r in records:
            f.write(r)


def lifted(record, metres, scale_z):
    r = bytearray(record)
    z = struct.unpack_from("<i", r, 8)[0]
    struct.pack_into("<i", r, 8, z + round(metres / scale_z))
    return r


def polygon_rings(wkb):
    """The rings of a WKB Polygon or MultiPolygon (2D or 3D), as lists of [x, y]."""
    e = "<" if wkb[0] == 1 else ">"
    kind = struct.unpack_from(e + "I", wkb, 1)[0]
    dims = 3 if kind > 1000 or kind & 0x80000000 else 2
    kind = (kind & 0xFFFF) % 1000
    at = 5

    def polygon(at):
        rings = []
        count = struct.unpack_from(e + "I", wkb, at)[0]
        at += 4
        for _ in range(count):
            n = struct.unpack_from(e + "I", wkb, at)[0]
            at += 4
            ring = []
            for _ in range(n):
                ring.append(list(struct.unpack_from(e + "2d", wkb, at)))
                at += 8 * dims
            rings.append(ring)
        return rings, at

    if kind == 3:
        return [polygon(at)[0]]
    out = []
    for _ in range(struct.unpack_from(e + "I", wkb, at)[0]):
        rings, at = polygon(at + 4 + 5)
        out.append(rings)
    return out


def sample_footprints():
    """{gml_id: MultiPolygon coordinates} of the sample's GeoPackage (SQLite: its geometry blobs read here)."""
    import sqlite3
    con = sqlite3.connect(SAMPLE_FOOTPRINTS)
    out = {}
    for gml_id, blob in con.execute("SELECT gml_id, GEOMETRY FROM buildingpart"):
        envelope = {0: 0, 1: 32, 2: 48, 3: 48, 4: 64}[(blob[3] >> 1) & 7]
        out[gml_id] = polygon_rings(blob[8 + envelope:])
    con.close()
    return out


def sample_geojson(path):
    features = [{"type": "Feature", "properties": {"gml_id": k},
                 "geometry": {"type": "MultiPolygon", "coordinates": v}} for k, v in sample_footprints().items()]
    with open(path, "w") as f:
        json.dump({"type": "FeatureCollection", "features": features}, f)


def cases(work):
    """{name: (arguments of `city3d reconstruct` but -o, the id of the row to show or None)}."""
    out = {}
    # Delft's tile 2 without its building class.
    header, records = read_las(os.path.join(DELFT, "ahn3_cropped_2.las"))
    for r in records:
        if r[15] & 31 == 6:
            r[15] = (r[15] & ~31) | 1
    unclassified = os.path.join(work, "tile2_unclassified.las")
    write_las(unclassified, header, records)
    out["unclassified tile"] = ([os.path.join(DELFT, "ahn3_cropped_1.las"), unclassified, "-f",
                                 os.path.join(DELFT, "footprints", "bgt_pand_laz_area.gpkg"), "--id-field", "gml_id"],
                                "b1105d28c-00ba-11e6-b420-2bdcc4ab5d7f")
    sample = ["-f", SAMPLE_FOOTPRINTS, "--id-field", "gml_id"]
    header, records = read_las(SAMPLE_TILES[0])
    scale_z = struct.unpack_from("<d", header, 147)[0]
    withheld = []
    for r in records:
        withheld.append(r)
        if r[15] & 31 == 6:
            copy = lifted(r, 3.0, scale_z)
            copy[15] |= 0x80
            withheld.append(copy)
    path = os.path.join(work, "withheld.las")
    write_las(path, header, withheld)
    out["withheld copies"] = ([path, SAMPLE_TILES[1]] + sample, "b11282799-00ba-11e6-b420-2bdcc4ab5d7f")
    tiles = []
    for k, tile in enumerate(SAMPLE_TILES):
        header, records = read_las(tile)
        path = os.path.join(work, f"ground50_{k}.las")
        write_las(path, header, [lifted(r, 50.0, scale_z) if r[15] & 31 == 2 else r for r in records])
        tiles.append(path)
    out["ground +50 m"] = (tiles + sample, "b11282799-00ba-11e6-b420-2bdcc4ab5d7f")
    out["ground class 0"] = (SAMPLE_TILES + sample + ["--ground-class", "0"], "b11282794-00ba-11e6-b420-2bdcc4ab5d7f")
    out["ignore classes"] = (SAMPLE_TILES + sample + ["--ignore-classes"], "b11282794-00ba-11e6-b420-2bdcc4ab5d7f")
    geojson = os.path.join(work, "rfc7946.geojson")
    sample_geojson(geojson)
    out["GeoJSON without crs"] = (SAMPLE_TILES + ["-f", geojson, "--id-field", "gml_id"], None)
    header, records = read_las(SAMPLE_TILES[0])
    path = os.path.join(work, "count_halved.las")
    write_las(path, header, records, count=len(records) // 2)
    out["count halved"] = ([path, SAMPLE_TILES[1]] + sample, None)
    # One building's points (the sample's b11282799: those in its footprint's box) and a noise point (class
    # 7) 30 m below them, as a single-building cloud.
    ring = sample_footprints()["b11282799-00ba-11e6-b420-2bdcc4ab5d7f"][0][0]
    x0, x1 = min(p[0] for p in ring), max(p[0] for p in ring)
    y0, y1 = min(p[1] for p in ring), max(p[1] for p in ring)
    header, records = read_las(SAMPLE_TILES[0])
    offset = struct.unpack_from("<3d", header, 155)
    scale = struct.unpack_from("<3d", header, 131)
    own = [r for r in records if r[15] & 31 == 6
           and x0 <= struct.unpack_from("<i", r, 0)[0] * scale[0] + offset[0] <= x1
           and y0 <= struct.unpack_from("<i", r, 4)[0] * scale[1] + offset[1] <= y1]
    noise = lifted(own[0], -30.0, scale_z)
    noise[15] = (noise[15] & ~31) | 7
    path = os.path.join(work, "noise_floor.las")
    write_las(path, header, own + [noise])
    out["noise floor"] = ([path], "noise_floor")
    return out


def run(city3d, arguments, out):
    done = subprocess.run([city3d, "reconstruct", *arguments, "--no-progress", "-o", out], capture_output=True,
                          text=True)
    warnings = [line for line in done.stderr.splitlines() if line.startswith("warning:") and "record no CRS" not in line]
    rows = []
    if os.path.exists(os.path.join(out, "report.csv")):
        with open(os.path.join(out, "report.csv")) as f:
            rows = list(csv.DictReader(f))
    crs = ""
    city = os.path.join(out, "buildings.city.json")
    if os.path.exists(city):
        with open(city) as f:
            crs = json.load(f).get("metadata", {}).get("referenceSystem", "")
    return done.returncode, rows, warnings, crs


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--city3d", default=os.path.join(HERE, "..", "build", "city3d"))
    parser.add_argument("--baseline")
    args = parser.parse_args()
    builds = [("baseline", args.baseline)] if args.baseline else []
    builds.append(("city3d", args.city3d))
    with tempfile.TemporaryDirectory() as work:
        print("| case | build | exit | statuses | the row shown: status, ground_z, ground_method, h_ridge, "
              "building_coverage, points | CRS written | warnings, note or reason |")
        print("| --- | --- | --- | --- | --- | --- | --- |")
        for name, (arguments, shown) in cases(work).items():
            for label, binary in builds:
                code, rows, warnings, crs = run(binary, arguments, os.path.join(work, name.replace(" ", "_") + label))
                statuses = {}
                for r in rows:
                    statuses[r["status"]] = statuses.get(r["status"], 0) + 1
                row = next((r for r in rows if r["id"] == shown), None)
                figures = ""
                said = "; ".join(w[9:80] for w in warnings[:2])
                if row:
                    figures = (f"{row['status']}, {row['ground_z']}, {row['ground_method']}, {row['h_ridge']}, "
                               f"{row.get('building_coverage', '')}, {row['points']}")
                    said = (said + " / " if said else "") + (row["reason"] or row["note"])[:110]
                text = ", ".join(f"{n} {s}" for s, n in sorted(statuses.items()))
                print(f"| {name} | {label} | {code} | {text} | {figures} | {crs.rsplit('/', 1)[-1]} | {said} |")


if __name__ == "__main__":
    main()
