#!/usr/bin/python3
"""A voxlight classroom lightmap against the Cycles reference here: means, relative RMSE
(RMSE / reference mean, RGB pooled, over the reference mask's covered texels) of the total,
direct and indirect (total - direct) lightmaps; then the same without the texels Cycles
leaves black (faces in contact with others, see README.md). Needs numpy and oiiotool.

    /usr/bin/python3 tests/reference/classroom/compare_lightmap.py OUTPUT_DIR [SPP]

OUTPUT_DIR holds lightmap.exr and lightmap_direct.exr (a `voxlight bake` of
classroom_baked.json, or the bench's vct point folder). SPP picks the reference (default 1024).
"""
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def read_exr(path):
    """float64 H x W x 3, rows from the top (oiiotool -> FITS, whose rows run bottom-up)."""
    with tempfile.TemporaryDirectory() as tmp:
        fits = os.path.join(tmp, "x.fits")
        subprocess.run(["oiiotool", path, "-d", "float", "-o", fits], check=True)
        data = open(fits, "rb").read()
    info = subprocess.run(["oiiotool", "--info", path], capture_output=True, text=True, check=True).stdout
    # "path :  512 x  512, 3 channel, float openexr"
    size, channels = info.split(":", 1)[1].split(",")[:2]
    w, h = (int(v) for v in size.split("x"))
    c = int(channels.split()[0])
    n = w * h * c * 4  # the image is the file's last n bytes (oiiotool pads after its header)
    a = np.flipud(np.frombuffer(data[len(data) - n:], ">f4").reshape(h, w, c)).astype(np.float64)
    return np.repeat(a, 3, axis=2) if c == 1 else a[..., :3]


def main():
    out = sys.argv[1]
    spp = sys.argv[2] if len(sys.argv) > 2 else "1024"
    ref = {k: read_exr(os.path.join(HERE, "classroom_lightmap_%s%sspp.exr" % (k, spp)))
           for k in ("", "direct_")}
    mask = read_exr(os.path.join(HERE, "classroom_lightmap_mask.exr"))[..., 0] > 0.5
    got = {"": read_exr(os.path.join(out, "lightmap.exr")),
           "direct_": read_exr(os.path.join(out, "lightmap_direct.exr"))}
    parts = {"total": (got[""], ref[""]), "direct": (got["direct_"], ref["direct_"]),
             "indirect": (got[""] - got["direct_"], ref[""] - ref["direct_"])}
    black = mask & (ref[""].sum(-1) == 0.0)
    for label, m in (("all %d covered texels" % mask.sum(), mask),
                     ("without the %d texels Cycles leaves black" % black.sum(), mask & ~black)):
        print(label)
        for name, (a, b) in parts.items():
            rel = np.sqrt(((a[m] - b[m]) ** 2).mean()) / b[m].mean()
            print("  %-8s rel. RMSE %6.2f%%   mean voxlight %s  Cycles %s  (ratio %s)" % (
                name, 100 * rel, np.round(a[m].mean(0), 4), np.round(b[m].mean(0), 4),
                np.round(a[m].mean(0) / b[m].mean(0), 4)))


if __name__ == "__main__":
    main()
