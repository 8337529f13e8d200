#!/usr/bin/python3
"""Where a lightmap-lit view's error lies: over the pixels a sun lights directly (dilated 2 px)
and over the rest, against a reference render. Relative RMSE (RMSE over the set's reference
mean, RGB pooled) of each set, and the sun pixels' share of the squared error.

    /usr/bin/python3 tools/accuracy/sun_pixels.py REFERENCE.exr SUN_DIRECT.exr VIEW.exr... [--below F]

SUN_DIRECT: the sun's direct light in the view, e.g. image_direct.exr of a bake of the same job
with the sky at 0 (its only light the sun); a pixel is the sun's where it exceeds 1% of the
reference's mean. --below F splits the sun pixels at F of the image's height (rows below it:
a room's floor). Needs numpy and OpenImageIO's Python module (docs/light-bake-modes.md).
"""
import sys

import numpy as np
import OpenImageIO as oiio


def read(path):
    return oiio.ImageBuf(path).get_pixels(oiio.FLOAT)[..., :3].astype(np.float64)


def main():
    args = sys.argv[1:]
    below = None
    if "--below" in args:
        i = args.index("--below")
        below = float(args[i + 1])
        del args[i:i + 2]
    if len(args) < 3:
        sys.exit(__doc__)
    ref, sun = read(args[0]), read(args[1]).mean(-1)
    sunlit = sun > 0.01 * ref.mean()
    for _ in range(2):
        grown = sunlit.copy()
        grown[1:] |= sunlit[:-1]
        grown[:-1] |= sunlit[1:]
        grown[:, 1:] |= sunlit[:, :-1]
        grown[:, :-1] |= sunlit[:, 1:]
        sunlit = grown
    sets = [("whole", np.ones_like(sunlit)), ("sun pixels", sunlit), ("rest", ~sunlit)]
    if below is not None:
        rows = np.arange(ref.shape[0])[:, None] >= below * ref.shape[0]
        sets += [("sun pixels below %.2f" % below, sunlit & rows), ("sun pixels above", sunlit & ~rows)]
    print("sun pixels: %.1f%% of the view" % (100 * sunlit.mean()))
    for path in args[2:]:
        d2 = ((read(path) - ref) ** 2).sum(-1)
        parts = ["%s %.2f%%" % (name, 100 * np.sqrt(d2[sel].mean() / 3) / ref[sel].mean()) for name, sel in sets]
        print("%s: %s; the sun pixels hold %.0f%% of the squared error" % (path, ", ".join(parts), 100 * d2[sunlit].sum() / d2.sum()))


if __name__ == "__main__":
    main()
