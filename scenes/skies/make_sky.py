#!/usr/bin/env python3
# Makes scenes/skies/afternoon.exr, the image sky of the Cycles references in
# tests/reference/sky/: a 512 x 256 equirectangular HDR, RGB half float, ZIP-compressed,
# linear radiance in W/(m^2 sr). Deterministic (no randomness; the same bytes every run
# with the same numpy and oiiotool).
#
#   /usr/bin/python3 scenes/skies/make_sky.py [--out scenes/skies/afternoon.exr]
#
# Needs python3 with numpy (Debian's /usr/bin/python3 has it) and OpenImageIO's `oiiotool` (Debian: openimageio-tools); the
# float pixels go to oiiotool as a PFM and come out as the EXR.
#
# Layout (the equirectangular convention of tests/reference/sky/README.md, in glTF
# coordinates, +Y up): column x (from the left edge, continuous) and row y (from the top
# edge) of a W x H image look along
#   azimuth   phi = 2 pi (x / W - 1/2)   (phi = atan2(d.z, d.x): x = W/2 is +X, x = W/4 is -Z)
#   elevation e   = pi (1/2 - y / H)     (y = 0 is the zenith, y = H/2 the horizon)
# Content:
# - sky above the horizon: horizon (0.9, 0.95, 1.0) blending to zenith (0.35, 0.55, 1.0)
#   as f = sin(e)^0.6;
# - ground below the horizon: (0.25, 0.2, 0.15), uniform; the horizon is the boundary
#   between rows H/2 - 1 and H/2;
# - a sun disc 6 degrees across (angular radius 3 degrees) of radiance (300, 280, 250),
#   centred at column 0.7 W = 358.4 (azimuth atan2(d.z, d.x) = 72 degrees: from +Z, a little
#   +X, so that it shines into the open front and top of the Cornell sky box at rotation 0)
#   and elevation 35 degrees (row 78.22), the sun's direction d = (0.2531, 0.5736, 0.7791);
#   its edge pixels anti-aliased by 8 x 8 supersampling of each pixel's angular footprint;
# - a glow around it: (8, 7, 5) * exp(-(gamma - 3 deg) / 4 deg) outside the disc (gamma the
#   angle from the sun's centre), added to sky and ground alike.
import argparse
import os
import subprocess
import tempfile

import numpy as np

W, H = 512, 256
ZENITH = np.array([0.35, 0.55, 1.0])
HORIZON = np.array([0.9, 0.95, 1.0])
GROUND = np.array([0.25, 0.2, 0.15])
SUN = np.array([300.0, 280.0, 250.0])
SUN_RADIUS = np.radians(3.0)
SUN_COLUMN = 0.7 * W
SUN_ELEVATION = np.radians(35.0)
GLOW = np.array([8.0, 7.0, 5.0])
GLOW_SCALE = np.radians(4.0)
SUPER = 8


def direction(x, y):
    """glTF unit direction of continuous image coordinates (x from the left, y from the top)."""
    x, y = np.broadcast_arrays(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))
    phi = 2.0 * np.pi * (x / W - 0.5)
    e = np.pi * (0.5 - y / H)
    return np.stack([np.cos(e) * np.cos(phi), np.sin(e), np.cos(e) * np.sin(phi)], axis=-1)


def make():
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float64)
    centre = direction(xs + 0.5, ys + 0.5)
    elevation = np.arcsin(np.clip(centre[..., 1], -1.0, 1.0))
    f = np.sin(np.clip(elevation, 0.0, None)) ** 0.6
    sky = HORIZON * (1.0 - f[..., None]) + ZENITH * f[..., None]
    image = np.where((ys < H / 2)[..., None], sky, GROUND)
    sun_dir = direction(np.array(SUN_COLUMN), np.array(H * (0.5 - SUN_ELEVATION / np.pi)))
    gamma = np.arccos(np.clip(centre @ sun_dir, -1.0, 1.0))
    image += GLOW * np.exp(-np.clip(gamma - SUN_RADIUS, 0.0, None) / GLOW_SCALE)[..., None] \
        * (gamma > SUN_RADIUS)[..., None]
    # The disc: the share of each pixel's SUPER x SUPER sub-positions inside the disc,
    # computed only near the sun.
    near = np.argwhere(gamma < SUN_RADIUS + np.radians(2.0))
    offsets = (np.arange(SUPER) + 0.5) / SUPER
    for y, x in near:
        sub = direction(x + offsets[None, :], y + offsets[:, None])
        g = np.arccos(np.clip(sub @ sun_dir, -1.0, 1.0))
        inside = float(np.mean(g < SUN_RADIUS))
        if inside > 0.0:
            # Inside the disc the sun replaces sky and glow; at the edge the two blend.
            image[y, x] = inside * SUN + (1.0 - inside) * image[y, x]
    return image.astype(np.float32)


def write_exr(path, image):
    h, w = image.shape[:2]
    with tempfile.TemporaryDirectory() as tmp:
        pfm = os.path.join(tmp, "sky.pfm")
        with open(pfm, "wb") as out:
            out.write(b"PF\n%d %d\n-1.0\n" % (w, h))  # little-endian floats, rows bottom-up
            out.write(np.ascontiguousarray(np.flipud(image)).astype("<f4").tobytes())
        subprocess.run(["oiiotool", "--nosoftwareattrib", pfm,
                        "-d", "half", "--compression", "zip",
                        "--attrib", "oiio:ColorSpace", "Linear",
                        "--attrib", "DateTime", "2026:11:27 00:00:00", "-o", path], check=True)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "afternoon.exr"))
    args = parser.parse_args()
    write_exr(args.out, make())


if __name__ == "__main__":
    main()
