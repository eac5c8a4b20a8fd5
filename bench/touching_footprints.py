#!/usr/bin/env python3
"""Footprints whose rings touch, on real points: three footprints made from one Delft building
(b112715f4, 120 m2, the fourth largest single-ring footprint of the block) and reconstructed from both
AHN3 tiles, each by every build given:

  - touch:  its own polygon with a triangular courtyard whose corner lies on its first vertex;
  - corner: two quarters of its bounding box that meet at the box's centre (a MultiPolygon);
  - holes:  its bounding box with two square courtyards that share a corner at the box's centre.

All three are valid in OGC's rules, and every solid extruded from them has an edge of four faces where
the rings touch. Prints each build's status, level, RMSE, unsupported area, faces and note.

    python3 bench/touching_footprints.py [--city3d build/city3d] [--baseline OTHER/city3d]

Needs python3 and ogr2ogr (gdal-bin).
"""
import argparse
import csv
import json
import os
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
DELFT = os.path.normpath(os.path.join(HERE, "..", "..", "shared", "data", "ahn3_delft"))
CRS = {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::28992"}}


def twice_area(ring):
    return sum(ring[i][0] * ring[i + 1][1] - ring[i + 1][0] * ring[i][1] for i in range(len(ring) - 1))


def cases(work):
    """Writes the three footprints as GeoJSON; returns {name: path}."""
    layer = os.path.join(work, "all.geojson")
    subprocess.run(["ogr2ogr", "-f", "GeoJSON", layer, os.path.join(DELFT, "footprints", "bgt_pand_laz_area.gpkg")],
                   check=True)
    with open(layer) as f:
        features = json.load(f)["features"]
    single = [f for f in features if f["geometry"]["type"] == "Polygon" and len(f["geometry"]["coordinates"]) == 1]
    single.sort(key=lambda f: (-abs(twice_area(f["geometry"]["coordinates"][0])), f["properties"]["gml_id"]))
    ring = single[3]["geometry"]["coordinates"][0]
    xs, ys = [p[0] for p in ring], [p[1] for p in ring]
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    mx, my = (x0 + x1) / 2, (y0 + y1) / 2
    # touch: a triangle from the first vertex halfway to the centroid, clockwise.
    cx, cy = sum(xs[:-1]) / (len(xs) - 1), sum(ys[:-1]) / (len(ys) - 1)
    p = ring[0]
    dx, dy = cx - p[0], cy - p[1]
    q = [p[0] + 0.5 * dx, p[1] + 0.5 * dy]
    hole = [p, [q[0] - 0.15 * dy, q[1] + 0.15 * dx], [q[0] + 0.15 * dy, q[1] - 0.15 * dx], p]
    if twice_area(hole) > 0:
        hole = hole[::-1]
    w, h = (x1 - x0) / 6, (y1 - y0) / 6
    geometries = {
        "touch": {"type": "Polygon", "coordinates": [ring, hole]},
        "corner": {"type": "MultiPolygon", "coordinates": [
            [[[x0, y0], [mx, y0], [mx, my], [x0, my], [x0, y0]]],
            [[[mx, my], [x1, my], [x1, y1], [mx, y1], [mx, my]]]]},
        "holes": {"type": "Polygon", "coordinates": [
            [[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]],
            [[mx - w, my - h], [mx - w, my], [mx, my], [mx, my - h], [mx - w, my - h]],
            [[mx, my], [mx, my + h], [mx + w, my + h], [mx + w, my], [mx, my]]]},
    }
    paths = {}
    for name, geometry in geometries.items():
        paths[name] = os.path.join(work, name + ".geojson")
        with open(paths[name], "w") as f:
            json.dump({"type": "FeatureCollection", "crs": CRS, "features": [
                {"type": "Feature", "properties": {"gml_id": name}, "geometry": geometry}]}, f)
    return paths


def run(city3d, footprints, out):
    subprocess.run([city3d, "reconstruct", os.path.join(DELFT, "ahn3_cropped_1.las"),
                    os.path.join(DELFT, "ahn3_cropped_2.las"), "-f", footprints, "--id-field", "gml_id",
                    "--no-progress", "-q", "-o", out], check=False, capture_output=True)
    with open(os.path.join(out, "report.csv")) as f:
        return next(csv.DictReader(f))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--city3d", default=os.path.join(HERE, "..", "build", "city3d"))
    parser.add_argument("--baseline")
    args = parser.parse_args()
    builds = [("baseline", args.baseline)] if args.baseline else []
    builds.append(("city3d", args.city3d))
    with tempfile.TemporaryDirectory() as work:
        paths = cases(work)
        print("| footprint | build | status | level | RMSE (m) | unsupported (m2) | faces | note |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- |")
        for name, path in paths.items():
            for label, binary in builds:
                r = run(binary, path, os.path.join(work, name + "_" + label))
                print(f"| {name} | {label} | {r['status']} | {r['level']} | {r['rmse']} | {r['unsupported_area']} | "
                      f"{r['faces']} | {(r['reason'] or r['note'])[:90]} |")


if __name__ == "__main__":
    main()
