#!/usr/bin/python3
"""A heat map of one view against another: log2(IMAGE / REFERENCE) per pixel, from -1 (blue, too
dark by half) to +1 (red, twice too bright), on a grey copy of the reference; pixels whose
reference is under 2% of its mean are left grey (their ratio is noise). Scaled up 3x.
--blocks N compares N x N-pixel blocks' means instead (a noisy reference's speckle averaged out).

    /usr/bin/python3 tools/accuracy/view_heat.py IMAGE.exr REFERENCE.exr OUT.png [--blocks N]
"""
import sys

import numpy as np
import OpenImageIO as oiio


def read(path):
    return oiio.ImageBuf(path).get_pixels(oiio.FLOAT)[..., :3].astype(np.float64).mean(-1)


def blocks(image, n):
    h, w = image.shape[0] // n * n, image.shape[1] // n * n
    means = image[:h, :w].reshape(h // n, n, w // n, n).mean(axis=(1, 3))
    return np.repeat(np.repeat(means, n, axis=0), n, axis=1)


def main():
    args = sys.argv[1:]
    n = 1
    if "--blocks" in args:
        i = args.index("--blocks")
        n = int(args[i + 1])
        del args[i:i + 2]
    if len(args) != 3:
        sys.exit(__doc__)
    image, reference = read(args[0]), read(args[1])
    if n > 1:
        image, reference = blocks(image, n), blocks(reference, n)
    floor = 0.02 * reference.mean()
    ratio = np.log2(np.maximum(image, floor) / np.maximum(reference, floor))
    shown = np.abs(ratio).clip(0, 1) * (reference > floor)
    grey = 0.35 * (reference / (reference + reference.mean())) ** 0.5
    out = np.stack([grey * (1 - shown) + shown * (ratio > 0),
                    grey * (1 - shown),
                    grey * (1 - shown) + shown * (ratio < 0)], -1).astype(np.float32)
    buf = oiio.ImageBuf(oiio.ImageSpec(out.shape[1], out.shape[0], 3, oiio.FLOAT))
    buf.set_pixels(oiio.ROI(), out)
    buf = oiio.ImageBufAlgo.resize(buf, roi=oiio.ROI(0, 3 * out.shape[1], 0, 3 * out.shape[0], 0, 1, 0, 3),
                                   filtername="box")
    buf.write(args[2], "uint8")


if __name__ == "__main__":
    main()
