#!/usr/bin/env python3
"""Keeps every k-th point record of a LAS 1.0-1.3 file (point formats 0-5): a survey of 1/k the density.

Usage: bench/thin_las.py IN.las OUT.las K [--start S]
Writes the header and VLRs as they are, then records S, S+k, S+2k, ... (S = 0 by default), and sets the point
count, the counts by return and the bounds from the records kept. Issue 23 measures the models of the Delft
block at every 2nd, 4th and 8th record (about 2 points per m2 at every 4th, as in older or non-Dutch surveys)
against the full-density points (bench/thinned_delft.sh). Python 3 standard library only.
"""
import struct
import sys


def thin(src, dst, k, start=0):
    with open(src, "rb") as f:
        data = f.read()
    if data[:4] != b"LASF":
        raise SystemExit(f"{src}: not a LAS file")
    major, minor = data[24], data[25]
    if major != 1 or minor > 3:
        raise SystemExit(f"{src}: LAS {major}.{minor} (thin_las handles 1.0-1.3)")
    offset = struct.unpack_from("<I", data, 96)[0]
    fmt = data[104] & 0x3F
    size = struct.unpack_from("<H", data, 105)[0]
    count = struct.unpack_from("<I", data, 107)[0]
    if fmt > 5:
        raise SystemExit(f"{src}: point format {fmt} (thin_las handles 0-5)")
    scale = struct.unpack_from("<3d", data, 131)
    shift = struct.unpack_from("<3d", data, 155)
    kept = bytearray()
    by_return = [0] * 5
    lo = [float("inf")] * 3
    hi = [float("-inf")] * 3
    n = 0
    for i in range(start, count, k):
        record = data[offset + i * size: offset + (i + 1) * size]
        if len(record) < size:
            raise SystemExit(f"{src}: record {i} truncated")
        kept += record
        n += 1
        ret = record[14] & 0x07
        if 1 <= ret <= 5:
            by_return[ret - 1] += 1
        for axis, raw in enumerate(struct.unpack_from("<3i", record, 0)):
            v = raw * scale[axis] + shift[axis]
            lo[axis] = min(lo[axis], v)
            hi[axis] = max(hi[axis], v)
    header = bytearray(data[:offset])
    struct.pack_into("<I", header, 107, n)
    struct.pack_into("<5I", header, 111, *by_return)
    if n:
        struct.pack_into("<6d", header, 179, hi[0], lo[0], hi[1], lo[1], hi[2], lo[2])
    with open(dst, "wb") as f:
        f.write(header)
        f.write(kept)
    return n


def main():
    args = sys.argv[1:]
    start = 0
    if "--start" in args:
        i = args.index("--start")
        start = int(args[i + 1])
        del args[i:i + 2]
    if len(args) != 3:
        raise SystemExit(__doc__)
    n = thin(args[0], args[1], int(args[2]), start)
    print(f"{args[1]}: {n} points (1 record in {args[2]} of {args[0]})")


if __name__ == "__main__":
    main()
