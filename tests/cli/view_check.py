#!/usr/bin/python3
"""Checks a screenshot of `spherechain view` (tests/cli/view.cmake). Standard library only (zlib): a
PNG reader for the 8-bit RGB/RGBA, non-interlaced files headless Chromium writes.

view_check.py PNG --view x0,y0,x1,y1 [--contact-box x0,y0,x1,y1 --min-contact N] [--no-contact]
Counts, inside the 3D view's rectangle, pixels of the contact colour (#ff00ff, unlit and drawn over
everything) and pixels that are not the background (#1d1f24); inside the timeline below the view, pixels
of the pair bars (#d0783a / #ffb070). Prints the counts; exit 1 with the reason when a check fails.
"""
import argparse
import struct
import sys
import zlib


def read_png(path):
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        sys.exit(f"{path}: not a PNG")
    pos, idat, w = 8, [], None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or ctype not in (2, 6) or interlace:
                sys.exit(f"{path}: unsupported PNG (depth {depth}, colour type {ctype}, interlace {interlace})")
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat.append(body)
        pos += 12 + n
    raw = zlib.decompress(b"".join(idat))
    stride = w * bpp
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if f == 1:
            for i in range(bpp, stride):
                line[i] = (line[i] + line[i - bpp]) & 255
        elif f == 2:
            line = bytearray((a + b) & 255 for a, b in zip(line, prev))
        elif f == 3:
            for i in range(stride):
                left = line[i - bpp] if i >= bpp else 0
                line[i] = (line[i] + ((left + prev[i]) >> 1)) & 255
        elif f == 4:
            for i in range(stride):
                a = line[i - bpp] if i >= bpp else 0
                b = prev[i]
                c = prev[i - bpp] if i >= bpp else 0
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return w, h, bpp, rows


def rect(s):
    return [int(round(float(v))) for v in s.split(",")]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("png")
    ap.add_argument("--view", required=True, type=rect)
    ap.add_argument("--contact-box", type=rect)
    ap.add_argument("--min-contact", type=int, default=10)
    ap.add_argument("--no-contact", action="store_true")
    a = ap.parse_args()
    w, h, bpp, rows = read_png(a.png)
    vx0, vy0, vx1, vy1 = a.view
    vx1, vy1 = min(vx1, w), min(vy1, h)

    def pixels(x0, y0, x1, y1):
        for y in range(max(0, y0), min(h, y1)):
            row = rows[y]
            for x in range(max(0, x0), min(w, x1)):
                yield x, y, row[x * bpp], row[x * bpp + 1], row[x * bpp + 2]

    def is_contact(r, g, b):
        return r >= 235 and g <= 30 and b >= 235

    contact_in_view = drawn = 0
    for x, y, r, g, b in pixels(vx0, vy0, vx1, vy1):
        contact_in_view += is_contact(r, g, b)
        drawn += abs(r - 0x1d) + abs(g - 0x1f) + abs(b - 0x24) > 24
    area = max(1, (vx1 - vx0) * (vy1 - vy0))
    bars = sum(1 for _, _, r, g, b in pixels(vx0, vy1, vx1, h)
               if (abs(r - 0xd0) < 12 and abs(g - 0x78) < 12 and abs(b - 0x3a) < 12) or
               (abs(r - 0xff) < 12 and abs(g - 0xb0) < 12 and abs(b - 0x70) < 12))
    print(f"{a.png}: {w}x{h}; view {vx0},{vy0}..{vx1},{vy1}: {drawn} drawn pixels ({100.0 * drawn / area:.1f} %), "
          f"{contact_in_view} of the contact colour; timeline: {bars} pixels of the pair bars")
    fails = []
    if drawn < 0.03 * area:
        fails.append(f"the 3D view is almost empty ({drawn} pixels differ from the background)")
    if bars < 20:
        fails.append("no pair bars in the timeline")
    if a.contact_box:
        x0, y0, x1, y1 = a.contact_box
        inside = sum(is_contact(r, g, b) for _, _, r, g, b in pixels(x0 - 2, y0 - 2, x1 + 3, y1 + 3))
        print(f"  contact box {x0},{y0}..{x1},{y1}: {inside} pixels of the contact colour")
        if inside < a.min_contact:
            fails.append(f"only {inside} pixels of the contact colour where the contacts are (need {a.min_contact})")
    if a.no_contact and contact_in_view:
        fails.append(f"{contact_in_view} pixels of the contact colour on a frame without contacts")
    for f in fails:
        print("FAIL: " + f)
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
