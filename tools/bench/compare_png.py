#!/usr/bin/env python3
"""Two 8-bit sRGB PNGs of the same size compared as a viewer shows them: a screenshot of
`voxlight view --screenshot` against a bake's image.png or image_lightmapped.png.

    python3 tools/bench/compare_png.py A.png B.png [DIFF.png]

Over the pixels where neither image is clipped (no channel at 255): the relative RMSE of A
against B in linear light (RMSE / mean of B, RGB pooled, as metrics/metrics.h), and each
pixel's largest channel difference in codes (median, 90th and 99th percentile, largest, the
share within 2). DIFF.png, when named, is that difference × 4 in grey. The standard library
only (a PNG reader for 8-bit, non-interlaced images): nothing to install.
"""
import math
import struct
import sys
import zlib


def read_png(path):
    data = open(path, 'rb').read()
    if data[:8] != b'\x89PNG\r\n\x1a\n':
        sys.exit(f'{path}: not a PNG')
    pos, idat, width, height, depth, colour, interlace = 8, b'', 0, 0, 0, 0, 0
    while pos < len(data):
        length, = struct.unpack('>I', data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b'IHDR':
            width, height, depth, colour, _, _, interlace = struct.unpack('>IIBBBBB', body[:13])
        elif kind == b'IDAT':
            idat += body
    channels = {0: 1, 2: 3, 4: 2, 6: 4}.get(colour)
    if depth != 8 or channels is None or interlace:
        sys.exit(f'{path}: only 8-bit grey, RGB or RGBA, non-interlaced PNGs')
    raw, stride, rows, previous, at = zlib.decompress(idat), width * channels, [], bytearray(width * channels), 0
    for _ in range(height):
        kind, line = raw[at], bytearray(raw[at + 1:at + 1 + stride])
        at += 1 + stride
        for x in range(stride):
            left = line[x - channels] if x >= channels else 0
            up, corner = previous[x], previous[x - channels] if x >= channels else 0
            if kind == 1:
                line[x] = (line[x] + left) & 255
            elif kind == 2:
                line[x] = (line[x] + up) & 255
            elif kind == 3:
                line[x] = (line[x] + (left + up) // 2) & 255
            elif kind == 4:
                p = left + up - corner
                pa, pb, pc = abs(p - left), abs(p - up), abs(p - corner)
                line[x] = (line[x] + (left if pa <= pb and pa <= pc else up if pb <= pc else corner)) & 255
        rows.append([tuple(line[x * channels + min(c, channels - 1)] for c in range(3)) for x in range(width)])
        previous = line
    return width, height, rows


def linear(code):
    c = code / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    width, height, a = read_png(sys.argv[1])
    width_b, height_b, b = read_png(sys.argv[2])
    if (width, height) != (width_b, height_b):
        sys.exit(f'{width} x {height} against {width_b} x {height_b}')
    squared, reference, terms, codes = 0.0, 0.0, 0, []
    for y in range(height):
        for x in range(width):
            pa, pb = a[y][x], b[y][x]
            if max(pa) == 255 or max(pb) == 255:
                continue
            for c in range(3):
                squared += (linear(pa[c]) - linear(pb[c])) ** 2
                reference += linear(pb[c])
                terms += 1
            codes.append(max(abs(pa[c] - pb[c]) for c in range(3)))
    codes.sort()
    n = len(codes)
    print(f'{100.0 * n / (width * height):.1f}% of pixels unclipped: relative RMSE '
          f'{100.0 * math.sqrt(squared / terms) / (reference / terms):.2f}% in linear light; codes apart: median '
          f'{codes[n // 2]}, 90% {codes[int(0.9 * n)]}, 99% {codes[int(0.99 * n)]}, largest {codes[-1]}, '
          f'{100.0 * sum(1 for c in codes if c <= 2) / n:.1f}% within 2')
    if len(sys.argv) == 4:
        lines = b''.join(b'\x00' + bytes(min(255, 4 * max(abs(a[y][x][c] - b[y][x][c]) for c in range(3)))
                                        for x in range(width)) for y in range(height))

        def chunk(kind, body):
            return struct.pack('>I', len(body)) + kind + body + struct.pack('>I', zlib.crc32(kind + body) & 0xffffffff)

        with open(sys.argv[3], 'wb') as out:
            out.write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', width, height, 8, 0, 0, 0, 0)) +
                      chunk(b'IDAT', zlib.compress(lines)) + chunk(b'IEND', b''))


if __name__ == '__main__':
    main()
