#!/usr/bin/env python3
"""Writes the input of splintcore-bench's inflate_ct16_zlib6 line: 4 MiB of CT-like 16-bit
little-endian data (32 slices of 256 x 256: an ellipse of soft tissue with a bone ring, air
outside, +-20 HU of noise from a fixed seed) compressed by Python's zlib at level 6.
usage: python3 tools/bench/make_inflate_input.py OUT.zz
then:  splintcore-bench --filter inflate --inflate-input OUT.zz
"""
import random
import struct
import sys
import zlib


def main():
    rng = random.Random(31)
    side, slices = 256, 32
    rows = []
    for z in range(slices):
        for y in range(side):
            row = []
            for x in range(side):
                dx, dy = (x - 128) / 110.0, (y - 128) / (90.0 - z)
                r2 = dx * dx + dy * dy
                v = -1000 if r2 > 1 else (1200 if r2 > 0.8 else 40)
                row.append(v + (rng.randint(-20, 20) if v != -1000 else rng.randint(-3, 3)))
            rows.append(struct.pack("<%dh" % side, *row))
    plain = b"".join(rows)
    with open(sys.argv[1], "wb") as f:
        f.write(zlib.compress(plain, 6))
    print("%d -> %d bytes" % (len(plain), len(zlib.compress(plain, 6))))


if __name__ == "__main__":
    main()
