#!/usr/bin/env python3
"""Writes the tiny LAS and PLY fixtures of tests/test_point_cloud_io.cpp (valid and deliberately broken).

Run from anywhere: python3 tests/data/make_test_files.py. The output is deterministic and committed;
the values the tests expect are written here, next to the bytes that carry them.
"""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
LAS = os.path.join(HERE, "las")
PLY = os.path.join(HERE, "ply")

FORMAT_SIZE = [20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67]


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)


def vlr(user_id, record_id, payload):
    return (struct.pack("<H16sHH32s", 0, user_id.encode(), record_id, len(payload), b"city3d test")
            + payload)


def las(minor, fmt, points, scale=(0.01, 0.01, 0.01), offset=(0.0, 0.0, 0.0), vlrs=(),
        extra_bytes=0, record_length=None, count=None, format_byte=None, signature=b"LASF",
        major=1, evlr=None):
    """A LAS file. points: dicts with X Y Z (ints) and optional I ret nret cls gps rgb."""
    header_size = {3: 235, 4: 375}.get(minor, 227)
    rl = record_length if record_length is not None else FORMAT_SIZE[fmt] + extra_bytes
    vlr_bytes = b"".join(vlrs)
    offset_to_points = header_size + len(vlr_bytes)
    records = b""
    for p in points:
        r = struct.pack("<3iH", p["X"], p["Y"], p["Z"], p.get("I", 0))
        if fmt < 6:
            r += struct.pack("<BBbBH", p.get("ret", 1) | (p.get("nret", 1) << 3), p.get("cls", 0),
                             0, 0, 0)
            if fmt in (1, 3):
                r += struct.pack("<d", p.get("gps", 0.0))
            if fmt in (2, 3):
                r += struct.pack("<3H", *p.get("rgb", (0, 0, 0)))
        else:
            r += struct.pack("<BBBBhHd", p.get("ret", 1) | (p.get("nret", 1) << 4), 0,
                             p.get("cls", 0), 0, 0, 0, p.get("gps", 0.0))
            if fmt in (7, 8):
                r += struct.pack("<3H", *p.get("rgb", (0, 0, 0)))
            if fmt == 8:
                r += struct.pack("<H", 0)  # NIR
        r += bytes(range(1, 1 + extra_bytes))
        records += r.ljust(rl, b"\0")[:rl]
    n = len(points) if count is None else count
    xs = [p["X"] * scale[0] + offset[0] for p in points] or [0.0]
    ys = [p["Y"] * scale[1] + offset[1] for p in points] or [0.0]
    zs = [p["Z"] * scale[2] + offset[2] for p in points] or [0.0]
    h = signature + struct.pack("<HHIHH8s", 0, 0, 0, 0, 0, b"")
    h += struct.pack("<BB32s32sHH", major, minor, b"city3d", b"make_test_files.py", 1, 2024)
    h += struct.pack("<HIIBHI", header_size, offset_to_points, len(vlrs),
                     fmt if format_byte is None else format_byte, rl, n if fmt < 6 else 0)
    h += struct.pack("<5I", n, 0, 0, 0, 0)
    h += struct.pack("<3d3d", *scale, *offset)
    h += struct.pack("<6d", max(xs), min(xs), max(ys), min(ys), max(zs), min(zs))
    if minor >= 3:
        h += struct.pack("<Q", 0)
    if minor >= 4:
        evlr_start, evlr_count = (0, 0) if evlr is None else evlr
        h += struct.pack("<QIQ15Q", evlr_start, evlr_count, n, *([0] * 15))
    assert len(h) == header_size, len(h)
    return h + vlr_bytes + records


def geokeys(*keys):
    payload = struct.pack("<4H", 1, 1, 0, len(keys))
    for key, value in keys:
        payload += struct.pack("<4H", key, 0, 1, value)
    return payload


def ply(header_lines, body):
    return ("\n".join(["ply"] + header_lines + ["end_header"]) + "\n").encode() + body


def main():
    # --- valid LAS -------------------------------------------------------------------------
    # LAS 1.4, format 7 with 4 extra bytes: 4-bit returns (9 of 12), an 8-bit class (40), RGB,
    # and the CRS from GeoTIFF keys (ProjectedCSTypeGeoKey 3072 = 28992).
    pf7 = [
        dict(X=84916949, Y=447413300, Z=5977, I=34, ret=9, nret=12, cls=40, gps=228671.75,
             rgb=(1000, 2000, 65535)),
        dict(X=84916962, Y=447413363, Z=-5101, I=70, ret=2, nret=2, cls=6, gps=228672.5,
             rgb=(1, 2, 3)),
    ]
    write(os.path.join(LAS, "las14_pf7_extrabytes_geokeys.las"),
          las(4, 7, pf7, scale=(0.001, 0.001, 0.001), extra_bytes=4,
              vlrs=[vlr("LASF_Projection", 34735, geokeys((1024, 1), (3072, 28992)))]))

    # --- broken LAS (each named after its one problem) -------------------------------------
    one = [dict(X=100, Y=200, Z=300, I=7, cls=2)]
    good12 = las(2, 0, one)
    write(os.path.join(LAS, "broken", "empty.las"), b"")
    write(os.path.join(LAS, "broken", "truncated_header.las"), good12[:180])
    write(os.path.join(LAS, "broken", "wrong_signature.las"), las(2, 0, one, signature=b"LASX"))
    write(os.path.join(LAS, "broken", "point_count_exceeds_file.las"), las(2, 0, one, count=5000))
    write(os.path.join(LAS, "broken", "record_length_too_small.las"),
          las(2, 1, one, record_length=24))
    write(os.path.join(LAS, "broken", "many_header_problems.las"),
          las(1, 0, one, major=2, scale=(0.0, 0.01, float("nan")), format_byte=12))
    # int32 max * 1e300 overflows to infinity: point 1 (the second) must be rejected.
    write(os.path.join(LAS, "broken", "scale_overflow.las"),
          las(2, 0, [dict(X=1, Y=1, Z=1), dict(X=2147483647, Y=1, Z=1)],
              scale=(1e300, 0.01, 0.01)))
    write(os.path.join(LAS, "broken", "laz_bit_set.las"), las(2, 0, one, format_byte=0x80))
    # LAS 1.4 whose EVLR pointer is past the end of the file: a warning, the points still read.
    write(os.path.join(LAS, "broken", "evlr_pointer_past_eof.las"),
          las(4, 6, [dict(X=1, Y=2, Z=3, cls=2)], evlr=(10**9, 2)))

    # --- valid PLY ------------------------------------------------------------------------
    # ascii: a face element with a list before the vertices, an edge element after them,
    # an unknown vertex property (quality) to skip, class, colours and intensity.
    write(os.path.join(PLY, "ascii_faces_first.ply"), ply(
        ["format ascii 1.0", "comment faces come first on purpose",
         "element face 2", "property list uchar int vertex_indices",
         "element vertex 3", "property float x", "property float y", "property float quality",
         "property float z", "property uchar class", "property uchar red", "property uchar green",
         "property uchar blue", "property ushort intensity",
         "element edge 1", "property int vertex1", "property int vertex2"],
        b"3 0 1 2\n4 0 1 2 2\n"
        b"1.5 2.5 9 3.5 6 255 128 0 1000\n"
        b"-1 -2 9 -3 2 1 2 3 65535\n"
        b"1e3 2e-3 9 0 26 0 0 0 0\n"
        b"0 1\n"))
    # big endian: double xyz at RD New magnitudes, float normals, int16 label, ushort colours,
    # a face element with a list before the vertices and another one after them.
    verts = [(84916.949, 447413.300, 5.977, 0.0, 0.0, 1.0, 6, (65535, 0, 257)),
             (84808.3, 447641.299, -0.568, 0.5, -0.5, 0.70710677, 2, (1, 2, 3))]
    body = struct.pack(">B3i", 3, 0, 1, 1)
    for x, y, z, nx, ny, nz, label, rgb in verts:
        body += struct.pack(">3d3fh3H", x, y, z, nx, ny, nz, label, *rgb)
    body += struct.pack(">B3i", 3, 1, 0, 0)
    write(os.path.join(PLY, "big_endian_double.ply"), ply(
        ["format binary_big_endian 1.0",
         "element face 1", "property list uint8 int32 vertex_indices",
         "element vertex 2", "property float64 x", "property float64 y", "property float64 z",
         "property float32 nx", "property float32 ny", "property float32 nz", "property int16 label",
         "property uint16 red", "property uint16 green", "property uint16 blue",
         "element face2 1", "property list uchar int vertex_indices"], body))
    # little endian with aliases: double xyz, scalar_classification, scalar_intensity.
    body = b"".join(struct.pack("<3dBf", *v) for v in
                    [(0.25, -0.5, 100.125, 9, 17.0), (1e5, 2e5, -3e-3, 1, 65535.0)])
    write(os.path.join(PLY, "little_endian_scalar_fields.ply"), ply(
        ["format binary_little_endian 1.0", "element vertex 2",
         "property double x", "property double y", "property double z",
         "property uint8 scalar_classification", "property float scalar_intensity"], body))

    # --- broken PLY -----------------------------------------------------------------------
    write(os.path.join(PLY, "broken", "no_vertex_element.ply"), ply(
        ["format ascii 1.0", "element face 1", "property list uchar int vertex_indices"],
        b"3 0 1 2\n"))
    write(os.path.join(PLY, "broken", "vertex_list_property.ply"), ply(
        ["format ascii 1.0", "element vertex 1", "property float x", "property float y",
         "property float z", "property list uchar float weights"], b"1 2 3 2 0.5 0.5\n"))
    write(os.path.join(PLY, "broken", "nan_coordinate.ply"), ply(
        ["format ascii 1.0", "element vertex 3", "property float x", "property float y",
         "property float z"], b"1 2 3\n4 5 6\n7 nan 9\n"))
    write(os.path.join(PLY, "broken", "truncated_body.ply"), ply(
        ["format binary_little_endian 1.0", "element vertex 5", "property float x",
         "property float y", "property float z"],
        struct.pack("<6f", 1, 2, 3, 4, 5, 6) + struct.pack("<f", 7)))
    write(os.path.join(PLY, "broken", "missing_z.ply"), ply(
        ["format ascii 1.0", "element vertex 1", "property float x", "property float y"],
        b"1 2\n"))
    write(os.path.join(PLY, "broken", "non_numeric.ply"), ply(
        ["format ascii 1.0", "element vertex 2", "property float x", "property float y",
         "property float z"], b"1 2 3\n4 abc 6\n"))
    write(os.path.join(PLY, "broken", "no_format_line.ply"), ply(
        ["element vertex 1", "property float x", "property float y", "property float z"],
        b"1 2 3\n"))


if __name__ == "__main__":
    main()
