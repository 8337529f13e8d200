#!/usr/bin/env python3
"""Blotches: the tail of a lightmap's per-texel error against a lightmap of path-traced texels.

Issue 34 asks the 99th percentile of the per-texel relative error over covered texels, against
a reference whose noise is not counted. The reference is two seeds of `accuracy_pixel
--truth-lightmap` (every texel path-traced, as shipped); their mean is the truth. Its noise is
taken out by averaging, both in the bake and in the truth, each covered texel's 3 x 3 (or
wider) window of covered texels: charts are packed with a padding ring between them, so the
window of a covered texel holds no other chart's covered texel. What noise is left is shown
by the two seeds against each other in the same windows (the mean of two seeds deviates
from the truth by about half their difference). Grey (the mean of RGB) per texel.

  /usr/bin/python3 tools/accuracy/lightmap_blotches.py BAKE_DIR TRUTH_SEED1.exr TRUTH_SEED2.exr [HEAT.png]

BAKE_DIR holds the bake's lightmap.exr and lightmap_mask.exr (one atlas). HEAT.png, when
given, is the atlas's heat map over 3 x 3 windows: log2 bake / truth from -2 (blue, too dark)
to +2 (red, too bright), white where they agree; texels the truth finds under 10% of its
median dark grey, uncovered texels black.
"""
import sys

import numpy as np
import OpenImageIO as oiio


def read(path):
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        sys.exit(f"{path}: {buf.geterror()}")
    return buf.get_pixels(oiio.FLOAT)


def window_mean(values, mask, radius):
    """The mean of `values` over the covered texels of each texel's (2r+1)^2 window."""
    if radius == 0:
        return values
    covered = mask.astype(np.float64)
    padded_v = np.pad(np.where(mask, values, 0.0).astype(np.float64), radius)
    padded_m = np.pad(covered, radius)
    total = np.zeros_like(covered)
    count = np.zeros_like(covered)
    h, w = mask.shape
    for dy in range(2 * radius + 1):
        for dx in range(2 * radius + 1):
            total += padded_v[dy:dy + h, dx:dx + w]
            count += padded_m[dy:dy + h, dx:dx + w]
    return np.where(count > 0, total / np.maximum(count, 1.0), 0.0)


def main():
    if len(sys.argv) not in (4, 5):
        sys.exit(__doc__)
    bake_dir, seed1, seed2 = sys.argv[1:4]
    bake = read(f"{bake_dir}/lightmap.exr")[..., :3].mean(-1)
    mask = read(f"{bake_dir}/lightmap_mask.exr")[..., 0] > 0.5
    one, two = (read(p)[..., :3].mean(-1) for p in (seed1, seed2))
    if not (bake.shape == mask.shape == one.shape == two.shape):
        sys.exit("the bake's lightmap, its mask and the truth's texels differ in size")
    median = np.median(((one + two) / 2)[mask])
    print(f"covered texels {mask.sum()}, the truth's median {median:.4f}")
    for radius in (0, 1, 2):
        b, a1, a2 = (window_mean(x, mask, radius) for x in (bake, one, two))
        truth = (a1 + a2) / 2
        for floor in (0.0, 0.1):
            # Texels the truth finds all but black are mostly inside geometry (a foot on the
            # floor, a panel against a wall): nobody sees them, and their relative error is
            # without bound. Counted once (floor 0) and left out once (under 10% of the median).
            sel = mask & (truth > max(1e-4, floor * median))
            error = np.abs(b - truth)[sel] / truth[sel]
            noise = (np.abs(a1 - a2) / 2)[sel] / truth[sel]
            p = 100 * np.percentile(error, [50, 90, 99])
            n = 100 * np.percentile(noise, [50, 99])
            print(f"{2 * radius + 1}x{2 * radius + 1} windows, truth > {floor:g} x median "
                  f"({100 * sel.sum() / mask.sum():.1f}% of covered): p50 {p[0]:.1f}%  p90 {p[1]:.1f}%  "
                  f"p99 {p[2]:.1f}%  | the truth's noise p50 {n[0]:.1f}%  p99 {n[1]:.1f}%  | "
                  f"over 25%: {100 * (error > 0.25).mean():.1f}% of texels")
    if len(sys.argv) == 5:
        write_heat(sys.argv[4], window_mean(bake, mask, 1), window_mean((one + two) / 2, mask, 1), mask, median)


def write_heat(path, bake, truth, mask, median):
    lit = mask & (truth > 0.1 * median)
    # In steps of a quarter stop, so the map compresses.
    ratio = np.round(4 * np.clip(np.log2(np.maximum(bake, 1e-6) / np.maximum(truth, 1e-6)), -2.0, 2.0)) / 8.0
    heat = np.zeros(mask.shape + (3,), np.float32)
    heat[mask] = 0.25
    hot, cold = np.maximum(ratio, 0.0), np.maximum(-ratio, 0.0)
    heat[lit] = np.stack([1.0 - cold, 1.0 - np.maximum(hot, cold), 1.0 - hot], -1)[lit]
    out = oiio.ImageBuf(oiio.ImageSpec(mask.shape[1], mask.shape[0], 3, oiio.UINT8))
    out.set_pixels(oiio.ROI(0, mask.shape[1], 0, mask.shape[0], 0, 1, 0, 3), heat)
    if not out.write(path):
        sys.exit(f"{path}: {out.geterror()}")


if __name__ == "__main__":
    main()
