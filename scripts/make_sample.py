#!/usr/bin/env python3
"""Makes the small sample in data/ from ../shared/data/ahn3_delft (run once; the result is committed).

Crops both AHN3 LAS tiles (LAS 1.2, point format 1) to a box around 15 footprints that straddle the
tile seam at x = 85000, copying the point records unchanged and fixing the header's point counts and
bounds. The footprints themselves are cut with ogr2ogr (see data/README.md).
Usage: make_sample.py SRC.las DST.las XMIN YMIN XMAX YMAX
"""
import struct
import sys


def crop(src, dst, xmin, ymin, xmax, ymax):
    with open(src, "rb") as f:
        data = f.read()
    header_size, = struct.unpack_from("<H", data, 94)
    offset, = struct.unpack_from("<I", data, 96)
    rec_len, = struct.unpack_from("<H", data, 105)
    count, = struct.unpack_from("<I", data, 107)
    sx, sy, sz, ox, oy, oz = struct.unpack_from("<6d", data, 131)
    kept = []
    by_return = [0] * 5
    lo = [float("inf")] * 3
    hi = [float("-inf")] * 3
    for i in range(count):
        rec = data[offset + i * rec_len: offset + (i + 1) * rec_len]
        X, Y, Z = struct.unpack_from("<3i", rec, 0)
        x, y, z = X * sx + ox, Y * sy + oy, Z * sz + oz
        if xmin <= x <= xmax and ymin <= y <= ymax:
            kept.append(rec)
            r = rec[14] & 7
            if 1 <= r <= 5:
                by_return[r - 1] += 1
            for k, v in enumerate((x, y, z)):
                lo[k] = min(lo[k], v)
                hi[k] = max(hi[k], v)
    header = bytearray(data[:offset])
    struct.pack_into("<I", header, 107, len(kept))
    struct.pack_into("<5I", header, 111, *by_return)
    struct.pack_into("<6d", header, 179, hi[0], lo[0], hi[1], lo[1], hi[2], lo[2])
    with open(dst, "wb") as f:
        f.write(header)
        f.write(b"".join(kept))
    print(f"{dst}: {len(kept)} of {count} points, header {header_size} bytes")


if __name__ == "__main__":
    crop(sys.argv[1], sys.argv[2], *map(float, sys.argv[3:7]))
