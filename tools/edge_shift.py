#!/usr/bin/env python3
"""Pixel displacement between two renders of the same view (refraction on vs off), by block matching.

    python3 tools/edge_shift.py ON.png OFF.png X0 X1 Y0 Y1 [BLOCK] [RADIUS]

For every BLOCK×BLOCK block (default 12) inside the box [X0, X1) × [Y0, Y1) of ON.png whose pixels vary (checker
edges), finds the integer shift (dx, dy) within ±RADIUS (default 8) that best matches OFF.png (least squares,
each block normalised by its mean), and prints the shifts' distribution. Standard library only (8-bit RGB PNG).
"""
import struct
import sys
import zlib


def read_png(path):
    b = open(path, "rb").read()
    i, idat, w, h = 8, b"", 0, 0
    while i < len(b):
        n, = struct.unpack(">I", b[i:i + 4])
        t, d = b[i + 4:i + 8], b[i + 8:i + 8 + n]
        i += 12 + n
        if t == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", d[:10])
            if depth != 8 or ctype != 2:
                sys.exit(f"{path}: only 8-bit RGB PNGs (depth {depth}, colour type {ctype})")
        elif t == b"IDAT":
            idat += d
    raw, bpp = zlib.decompress(idat), 3
    stride, prev, p, rows = w * bpp, bytearray(w * bpp), 0, []
    for _ in range(h):
        f, line = raw[p], bytearray(raw[p + 1:p + 1 + stride])
        p += 1 + stride
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            c = prev[x - bpp] if x >= bpp else 0
            up = prev[x]
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + up) & 255
            elif f == 3:
                line[x] = (line[x] + (a + up) // 2) & 255
            elif f == 4:
                pp = a + up - c
                pa, pb, pc = abs(pp - a), abs(pp - up), abs(pp - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else up if pb <= pc else c)) & 255
        rows.append([line[3 * x] + line[3 * x + 1] + line[3 * x + 2] for x in range(w)])
        prev = line
    return w, h, rows


def main():
    if len(sys.argv) < 7:
        sys.exit(__doc__)
    _, w, h, on = (None, *read_png(sys.argv[1]))
    _, _, off = read_png(sys.argv[2])
    x0, x1, y0, y1 = map(int, sys.argv[3:7])
    block = int(sys.argv[7]) if len(sys.argv) > 7 else 12
    radius = int(sys.argv[8]) if len(sys.argv) > 8 else 8
    shifts = []
    for by in range(max(y0, radius), min(y1, h - radius) - block + 1, block):
        for bx in range(max(x0, radius), min(x1, w - radius) - block + 1, block):
            a = [on[y][x] for y in range(by, by + block) for x in range(bx, bx + block)]
            ma = sum(a) / len(a)
            if ma <= 0 or max(a) - min(a) < 0.5 * ma:
                continue  # no edge to follow
            best = None
            for dy in range(-radius, radius + 1):
                for dx in range(-radius, radius + 1):
                    bb = [off[y + dy][x + dx] for y in range(by, by + block) for x in range(bx, bx + block)]
                    mb = sum(bb) / len(bb)
                    if mb <= 0:
                        continue
                    e = sum((u / ma - v / mb) ** 2 for u, v in zip(a, bb))
                    if best is None or e < best[0]:
                        best = (e, dx, dy)
            if best:
                shifts.append((best[1], best[2], bx, by))
    if not shifts:
        sys.exit("no textured block in the box")
    mags = sorted((dx * dx + dy * dy) ** 0.5 for dx, dy, _, _ in shifts)
    moved = [s for s in shifts if s[0] or s[1]]
    print(f"{len(shifts)} blocks; {len(moved)} moved; largest shift {mags[-1]:.2f} px; median {mags[len(mags) // 2]:.2f} px")
    for dx, dy, bx, by in sorted(moved, key=lambda s: -(s[0] ** 2 + s[1] ** 2))[:10]:
        print(f"  block at ({bx}, {by}): ({dx:+d}, {dy:+d}) px")


main()
