#!/usr/bin/env python3
"""How far a camera image is from its reference, as docs/accuracy.md counts it.

  /usr/bin/python3 tools/accuracy/view_error.py IMAGE.exr REFERENCE.exr [--second IMAGE2.exr]

Relative RMSE (RMS of the difference over the reference's mean, RGB pooled, linear light) over
the bench's pixels (the reference at or below 5 in every channel: lamps seen directly are left
out), per pixel and over 4 x 4-pixel blocks (which take most of a reference's noise out), and
the means per channel against the reference's. With --second, IMAGE2 is the same bake at
another `lightmap-seed`: the bake's own noise is RMS(IMAGE - IMAGE2) / sqrt(2) over the same
pixels and blocks.
"""
import argparse
import sys

import numpy as np
import OpenImageIO as oiio


def read(path):
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        sys.exit(f"{path}: {buf.geterror()}")
    pixels = buf.get_pixels(oiio.FLOAT)
    if pixels is None or pixels.ndim != 3 or pixels.shape[2] < 3:
        sys.exit(f"{path}: not an RGB image")
    return pixels[..., :3].astype(np.float64)


def blocks(image):
    h, w = image.shape[0] // 4 * 4, image.shape[1] // 4 * 4
    return image[:h, :w].reshape(h // 4, 4, w // 4, 4, -1).mean(axis=(1, 3))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("image")
    parser.add_argument("reference")
    parser.add_argument("--second", help="the same bake at another lightmap-seed: its noise")
    args = parser.parse_args()
    image, reference = read(args.image), read(args.reference)
    if image.shape != reference.shape:
        sys.exit(f"{args.image} is {image.shape[1]} x {image.shape[0]}, {args.reference} "
                 f"{reference.shape[1]} x {reference.shape[0]}")
    pixels = (reference <= 5.0).all(axis=-1)
    block_pixels = blocks(pixels[..., None].astype(np.float64))[..., 0] == 1.0
    if not pixels.any():
        sys.exit(f"{args.reference}: no pixel at or below 5")

    def rel(a, b, mask):
        return 100.0 * np.sqrt(np.mean((a - b)[mask] ** 2)) / b[mask].mean()

    means = [100.0 * (image[pixels][:, c].mean() / reference[pixels][:, c].mean() - 1.0) for c in range(3)]
    print(f"per pixel {rel(image, reference, pixels):.2f}%  4x4 blocks "
          f"{rel(blocks(image), blocks(reference), block_pixels):.2f}%  means "
          f"{means[0]:+.2f} / {means[1]:+.2f} / {means[2]:+.2f}%  ({pixels.sum()} pixels)")
    if args.second:
        second = read(args.second)
        if second.shape != image.shape:
            sys.exit(f"{args.second}: not the size of {args.image}")
        noise = rel(image, second, pixels) / np.sqrt(2.0)
        noise_blocks = rel(blocks(image), blocks(second), block_pixels) / np.sqrt(2.0)
        print(f"noise per pixel {noise:.2f}%  4x4 blocks {noise_blocks:.2f}%")


if __name__ == "__main__":
    main()
