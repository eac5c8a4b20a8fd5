#!/usr/bin/env python3
"""A LAZ file of many chunks from the Delft block's two AHN3 LAZ tiles, for timing the LAZ decoder where a
file's chunk count does not cap its speed-up on several threads (issue 27).

The parallel unit of LAZ decoding is the chunk (one arithmetic-coded stream of 50,000 points here), so two
threads cannot decode ahn3_cropped_1.laz (13 chunks, the last one short) more than 1.88x faster than one,
whatever the decoder does. An AHN3 tile holds thousands of chunks. This script builds such a file without
a LAZ encoder: it copies the compressed chunks of both tiles into a grid of copies (as
bench/synthetic_tile.py does with the LAS tiles) and shifts each copy by rewriting the first point of
every chunk. That point is stored raw at the start of a chunk (LASzip's point-wise compressor, point
format 1: 20 bytes of the point, 8 of the GPS time), and every later point of the chunk is coded relative
to the one before, so moving the first point moves the whole chunk. Only full chunks are copied (the LASzip
VLR keeps its fixed chunk size); the chunk table is encoded anew with LASzip's integer compressor and
arithmetic coder, written here after the decoder in src/laz/arithmetic_decoder.hpp. Before it writes
anything, the script checks its coder against the input: the chunk tables it decodes from both tiles
must encode back to the same bytes.

    python3 bench/synthetic_laz.py OUT.laz [--grid 6x5]
    build/bench/bench_laz_decode OUT.laz 5 1,2     # 1 and 2 threads side by side

The header's point counts by return are set to 0 (the copied chunks' returns are not decoded here). Needs
python3 only.
"""
import argparse
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
DELFT = os.path.join(HERE, "..", "..", "shared", "data", "ahn3_delft")
TILES = [os.path.join(DELFT, "ahn3_cropped_1.laz"), os.path.join(DELFT, "ahn3_cropped_2.laz")]
# A copy every 300 m in x and 250 m in y (bench/synthetic_tile.py moves the LAS points and the footprints
# by these too): the block spans 264 x 229 m, so copies never overlap.
STEP_X, STEP_Y = 300.0, 250.0

MASK = 0xFFFFFFFF
MIN_LENGTH = 0x01000000
MAX_LENGTH = 0xFFFFFFFF
BIT_SHIFT, BIT_MAX = 13, 1 << 13
SYMBOL_SHIFT, SYMBOL_MAX = 15, 1 << 15


class BitModel:
    def __init__(self):
        self.zeros, self.count, self.prob = 1, 2, 1 << (BIT_SHIFT - 1)
        self.cycle = self.until = 4

    def update(self):
        self.count += self.cycle
        if self.count > BIT_MAX:
            self.count = (self.count + 1) >> 1
            self.zeros = (self.zeros + 1) >> 1
            if self.zeros == self.count:
                self.count += 1
        scale = 0x80000000 // self.count
        self.prob = ((self.zeros * scale) & MASK) >> (31 - BIT_SHIFT)
        self.cycle = min((5 * self.cycle) >> 2, 64)
        self.until = self.cycle


class SymbolModel:
    def __init__(self, symbols):
        self.symbols = symbols
        self.counts = [1] * symbols
        self.dist = [0] * symbols
        self.total = 0
        self.cycle = symbols
        self.update()
        self.until = self.cycle = (symbols + 6) >> 1

    def update(self):
        self.total += self.cycle
        if self.total > SYMBOL_MAX:
            self.counts = [(c + 1) >> 1 for c in self.counts]
            self.total = sum(self.counts)
        scale = 0x80000000 // self.total
        acc = 0
        for k in range(self.symbols):
            self.dist[k] = ((scale * acc) & MASK) >> (31 - SYMBOL_SHIFT)
            acc += self.counts[k]
        self.cycle = min((5 * self.cycle) >> 2, (self.symbols + 6) << 3)
        self.until = self.cycle

    def seen(self, symbol):
        self.counts[symbol] += 1
        self.until -= 1
        if self.until == 0:
            self.update()


class Decoder:
    def __init__(self, data):
        self.data, self.at = data, 4
        self.length = MAX_LENGTH
        self.value = int.from_bytes(data[:4], "big")

    def renormalise(self):
        while True:
            self.value = ((self.value << 8) & MASK) | self.data[self.at]
            self.at += 1
            self.length = (self.length << 8) & MASK
            if self.length >= MIN_LENGTH:
                break

    def bit(self, m):
        x = m.prob * (self.length >> BIT_SHIFT)
        if self.value < x:
            bit, self.length = 0, x
            m.zeros += 1
        else:
            bit = 1
            self.value -= x
            self.length -= x
        if self.length < MIN_LENGTH:
            self.renormalise()
        m.until -= 1
        if m.until == 0:
            m.update()
        return bit

    def symbol(self, m):
        whole = self.length
        self.length >>= SYMBOL_SHIFT
        lo, hi = 0, m.symbols  # the largest symbol whose start is not above the value
        while hi - lo > 1:
            mid = (lo + hi) >> 1
            if m.dist[mid] * self.length > self.value:
                hi = mid
            else:
                lo = mid
        x = m.dist[lo] * self.length
        y = m.dist[lo + 1] * self.length if lo != m.symbols - 1 else whole
        self.value -= x
        self.length = (y - x) & MASK
        if self.length < MIN_LENGTH:
            self.renormalise()
        m.seen(lo)
        return lo

    def raw(self, bits):
        if bits > 19:
            low = self.raw(16)
            return (self.raw(bits - 16) << 16) | low
        self.length >>= bits
        symbol = self.value // self.length
        self.value -= self.length * symbol
        if self.length < MIN_LENGTH:
            self.renormalise()
        return symbol


class Encoder:
    def __init__(self):
        self.out = bytearray()
        self.base, self.length = 0, MAX_LENGTH

    def carry(self):
        k = len(self.out) - 1
        while self.out[k] == 0xFF:
            self.out[k] = 0
            k -= 1
        self.out[k] += 1

    def advance(self, x, length):
        self.base += x
        if self.base > MASK:
            self.base &= MASK
            self.carry()
        self.length = length
        while self.length < MIN_LENGTH:
            self.out.append(self.base >> 24)
            self.base = (self.base << 8) & MASK
            self.length = (self.length << 8) & MASK

    def bit(self, m, bit):
        x = m.prob * (self.length >> BIT_SHIFT)
        if bit == 0:
            m.zeros += 1
            self.advance(0, x)
        else:
            self.advance(x, self.length - x)
        m.until -= 1
        if m.until == 0:
            m.update()

    def symbol(self, m, s):
        if s == m.symbols - 1:
            x = m.dist[s] * (self.length >> SYMBOL_SHIFT)
            self.advance(x, self.length - x)
        else:
            unit = self.length >> SYMBOL_SHIFT
            x = m.dist[s] * unit
            self.advance(x, m.dist[s + 1] * unit - x)
        m.seen(s)

    def raw(self, bits, value):
        if bits > 19:
            self.raw(16, value & 0xFFFF)
            value >>= 16
            bits -= 16
        unit = self.length >> bits
        self.advance(value * unit, unit)

    def done(self):
        another = True
        if self.length > 2 * MIN_LENGTH:
            x, length = MIN_LENGTH, MIN_LENGTH >> 1
        else:
            x, length = MIN_LENGTH >> 1, MIN_LENGTH >> 9
            another = False
        self.advance(x, length)
        self.out += bytes(3 if another else 2)  # the decoder reads ahead
        return bytes(self.out)


class IntegerCoder:
    """LASzip's integer compressor with 32-bit corrections (no folding), as the chunk table uses it."""

    def __init__(self, contexts, bits_high=8):
        self.bits_high = bits_high
        self.k_models = [SymbolModel(33) for _ in range(contexts)]
        self.bit0 = BitModel()
        self.correctors = [None] + [SymbolModel(1 << min(k, bits_high)) for k in range(1, 33)]

    def encode(self, enc, prediction, real, context):
        c = real - prediction
        c = (c + 2**31) % 2**32 - 2**31  # int32 arithmetic
        k = (-c if c <= 0 else c - 1).bit_length()
        enc.symbol(self.k_models[context], k)
        if k == 0:
            enc.bit(self.bit0, c)
        elif k < 32:
            c = c + (1 << k) - 1 if c < 0 else c - 1
            if k <= self.bits_high:
                enc.symbol(self.correctors[k], c)
            else:
                low = k - self.bits_high
                enc.symbol(self.correctors[k], c >> low)
                enc.raw(low, c & ((1 << low) - 1))

    def decode(self, dec, prediction, context):
        k = dec.symbol(self.k_models[context])
        if k == 0:
            c = dec.bit(self.bit0)
        elif k >= 32:
            c = -2**31
        else:
            if k <= self.bits_high:
                c = dec.symbol(self.correctors[k])
            else:
                low = k - self.bits_high
                c = (dec.symbol(self.correctors[k]) << low) | dec.raw(low)
            c = c + 1 if c >= 1 << (k - 1) else c - ((1 << k) - 1)
        return (prediction + c) & MASK


def encode_chunk_table(sizes):
    """The chunk table's coded entries for fixed-size chunks: each chunk's byte count from the last."""
    enc, coder, last = Encoder(), IntegerCoder(2), 0
    for size in sizes:
        coder.encode(enc, last, size, 1)
        last = size
    return enc.done()


def read_laz(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] != b"LASF":
        sys.exit(f"{path}: not a LAS/LAZ file")
    header_size, offset, vlrs = struct.unpack_from("<HII", data, 94)
    fmt, length = struct.unpack_from("<BH", data, 104)
    count = struct.unpack_from("<I", data, 107)[0]
    if fmt != 0x81 or length != 28:
        sys.exit(f"{path}: expected compressed point format 1 (28-byte records), got {fmt & 0x3F} ({length} bytes)")
    at, chunk_size = header_size, None
    for _ in range(vlrs):
        record_id, size = struct.unpack_from("<HH", data, at + 18)
        if data[at + 2:at + 18].rstrip(b"\0") == b"laszip encoded" and record_id == 22204:
            compressor = struct.unpack_from("<H", data, at + 54)[0]
            chunk_size = struct.unpack_from("<I", data, at + 54 + 12)[0]
            if compressor != 2 or chunk_size == 0xFFFFFFFF:
                sys.exit(f"{path}: expected LASzip's point-wise chunked compressor with fixed chunks")
        at += 54 + size
    if chunk_size is None:
        sys.exit(f"{path}: no LASzip VLR")
    table = struct.unpack_from("<q", data, offset)[0]
    version, chunks = struct.unpack_from("<II", data, table)
    if version != 0:
        sys.exit(f"{path}: chunk table version {version}")
    coded = data[table + 8:]
    dec, coder, sizes = Decoder(coded + bytes(8)), IntegerCoder(2), []
    for _ in range(chunks):
        sizes.append(coder.decode(dec, sizes[-1] if sizes else 0, 1))
    encoded = encode_chunk_table(sizes)
    if coded[:len(encoded)] != encoded:
        sys.exit(f"{path}: the chunk table does not encode back to its bytes (the coder here is wrong)")
    starts, at = [], offset + 8
    for size in sizes:
        starts.append(at)
        at += size
    if at != table:
        sys.exit(f"{path}: the chunk sizes add up to byte {at}, the chunk table is at {table}")
    points = [min(chunk_size, count - k * chunk_size) for k in range(chunks)]
    return dict(data=data, offset=offset, chunk_size=chunk_size, chunks=list(zip(starts, sizes, points)))


def make_laz(out_path, nx, ny):
    """Writes the LAZ of nx x ny copies to out_path; returns (points, chunks)."""
    tiles = [read_laz(t) for t in TILES]
    first = tiles[0]["data"]
    if any(t["data"][131:179] != first[131:179] or t["chunk_size"] != tiles[0]["chunk_size"] for t in tiles):
        sys.exit("the Delft tiles have different scales, offsets or chunk sizes")
    scale = struct.unpack_from("<3d", first, 131)
    dx_raw, dy_raw = round(STEP_X / scale[0]), round(STEP_Y / scale[1])
    header = bytearray(first[:tiles[0]["offset"]])
    body, sizes = bytearray(), []
    for row in range(ny):
        for col in range(nx):
            for t in tiles:
                for start, size, points in t["chunks"]:
                    if points != t["chunk_size"]:
                        continue  # a short last chunk would break the fixed chunk size
                    chunk = bytearray(t["data"][start:start + size])
                    x, y = struct.unpack_from("<ii", chunk, 0)
                    struct.pack_into("<ii", chunk, 0, x + col * dx_raw, y + row * dy_raw)
                    body += chunk
                    sizes.append(size)
    total = len(sizes) * tiles[0]["chunk_size"]
    if total >= 2**32:
        sys.exit("too many points for a LAS 1.2 header")
    struct.pack_into("<I", header, 107, total)
    struct.pack_into("<5I", header, 111, 0, 0, 0, 0, 0)
    bounds = [struct.unpack_from("<6d", t["data"], 179) for t in tiles]  # max x, min x, max y, min y, max z, min z
    struct.pack_into("<6d", header, 179, max(b[0] for b in bounds) + (nx - 1) * STEP_X, min(b[1] for b in bounds),
                     max(b[2] for b in bounds) + (ny - 1) * STEP_Y, min(b[3] for b in bounds),
                     max(b[4] for b in bounds), min(b[5] for b in bounds))
    table_at = len(header) + 8 + len(body)
    with open(out_path, "wb") as out:
        out.write(header)
        out.write(struct.pack("<q", table_at))
        out.write(body)
        out.write(struct.pack("<II", 0, len(sizes)))
        out.write(encode_chunk_table(sizes))
    return total, len(sizes)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("out")
    p.add_argument("--grid", default="6x5", help="copies in x and y (default 6x5: 480 chunks, 24 M points)")
    a = p.parse_args()
    nx, ny = (int(v) for v in a.grid.lower().split("x"))
    total, chunks = make_laz(a.out, nx, ny)
    print(f"{a.out}: {total:,} points in {chunks} chunks ({nx} x {ny} copies of the Delft block's full chunks), "
          f"{os.path.getsize(a.out) / 2**20:.0f} MB")

if __name__ == "__main__":
    main()
