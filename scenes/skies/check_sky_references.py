#!/usr/bin/env python3
# Sanity checks of the image-sky Cycles references in tests/reference/sky/, computed from the
# glTF file, the sky image and the mapping formula of that folder's README alone (no
# Blender): python3 with numpy, and oiiotool to read EXRs.
#
#   /usr/bin/python3 scenes/skies/check_sky_references.py
#
# 1. Camera renders: every pixel whose 4 x 4 sub-pixel rays (the 1-pixel box filter) all leave
#    the scene sees only sky; its expected value is the mean of the sky image, bilinear as
#    Cycles' Linear lookup, over those rays' directions d mapped by
#        x = W (1/2 + atan2(d'.z, d'.x) / (2 pi)),  y = H acos(d'.y) / pi,  d' = R_y(-rotation) d.
# 2. Direct lightmaps: at a few texels, E/pi = (1/pi) sum over the sky image of
#    L * max(0, n.d) * dOmega * visible(p, d), integrated with 2 x 2 sub-positions per image
#    pixel (8 x 8 around the sun), visibility by ray casting the glTF triangles; p and n are
#    the texel centre's point on its TEXCOORD_1 triangle. The window room's roof (the
#    exterior's top face, which nothing overhangs) sees the whole upper hemisphere: all its
#    texels should hold that one value, in the direct AND the total lightmap.
import json
import math
import os
import re
import struct
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
REF = os.environ.get("SKY_REFERENCE_DIR", os.path.join(ROOT, "tests", "reference", "sky"))


# ---- files ----------------------------------------------------------------------------------
def read_exr(path):
    """RGB float64, rows from the top (oiiotool -> FITS, whose rows run bottom-up)."""
    with tempfile.TemporaryDirectory() as tmp:
        fits = os.path.join(tmp, "x.fits")
        subprocess.run(["oiiotool", path, "--ch", "R,G,B", "-d", "float", "-o", fits], check=True)
        data = open(fits, "rb").read()
    header = data[:2880].decode("ascii", "replace")
    w = int(re.search(r"NAXIS2  =\s*(\d+)", header).group(1))
    h = int(re.search(r"NAXIS3  =\s*(\d+)", header).group(1))
    n = w * h * 3 * 4
    return np.flipud(np.frombuffer(data[len(data) - n:], ">f4").reshape(h, w, 3)).astype(np.float64)


def quat_matrix(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def load_gltf(path):
    """Triangles (T x 3 x 3), their TEXCOORD_1 (T x 3 x 2), geometric normals oriented like
    NORMAL, mesh names; and the first camera (position, rotation matrix, yfov, aspect).
    Top-level nodes only (the references' files have no hierarchy)."""
    g = json.load(open(path))
    base = os.path.dirname(path)
    buffers = [open(os.path.join(base, b["uri"]), "rb").read() for b in g["buffers"]]

    def accessor(i):
        a = g["accessors"][i]
        view = g["bufferViews"][a["bufferView"]]
        kind = {5126: "<f4", 5125: "<u4", 5123: "<u2", 5121: "u1"}[a["componentType"]]
        n = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[a["type"]]
        start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
        stride = view.get("byteStride", 0) or np.dtype(kind).itemsize * n
        raw = np.frombuffer(buffers[view["buffer"]], dtype=np.uint8, count=stride * (a["count"] - 1) + np.dtype(kind).itemsize * n, offset=start)
        out = np.lib.stride_tricks.as_strided(raw, shape=(a["count"], np.dtype(kind).itemsize * n), strides=(stride, 1))
        return np.frombuffer(out.copy().tobytes(), dtype=kind).reshape(a["count"], n).astype(np.float64)

    tris, uvs, normals, names, camera = [], [], [], [], None
    for node in g["nodes"]:
        assert "children" not in node
        m = np.eye(3) * np.array(node.get("scale", [1, 1, 1]))
        r = quat_matrix(node.get("rotation", [0, 0, 0, 1]))
        t = np.array(node.get("translation", [0, 0, 0]), dtype=np.float64)
        if "camera" in node:
            cam = g["cameras"][node["camera"]]["perspective"]
            camera = (t, r, cam["yfov"], cam.get("aspectRatio", 1.0))
        if "mesh" not in node:
            continue
        mesh = g["meshes"][node["mesh"]]
        for prim in mesh["primitives"]:
            pos = accessor(prim["attributes"]["POSITION"]) @ (r @ m).T + t
            uv1 = accessor(prim["attributes"]["TEXCOORD_1"])
            nrm = accessor(prim["attributes"]["NORMAL"]) @ r.T
            idx = accessor(prim["indices"]).astype(int).reshape(-1, 3)
            tri = pos[idx]
            gn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            gn /= np.linalg.norm(gn, axis=1, keepdims=True)
            gn *= np.sign(np.sum(gn * nrm[idx].mean(axis=1), axis=1, keepdims=True))
            tris.append(tri)
            uvs.append(uv1[idx])
            normals.append(gn)
            names += [mesh["name"]] * len(idx)
    return np.concatenate(tris), np.concatenate(uvs), np.concatenate(normals), names, camera


# ---- geometry and sky ------------------------------------------------------------------------
def hits(origins, dirs, tris, chunk=1 << 18):
    """True where a ray (origin, direction) hits any triangle at t > 1e-6 (Moller-Trumbore)."""
    out = np.zeros(len(dirs), dtype=bool)
    for s in range(0, len(dirs), chunk):
        o = np.broadcast_to(origins, dirs.shape)[s:s + chunk]
        d = dirs[s:s + chunk]
        hit = np.zeros(len(d), dtype=bool)
        for a, b, c in tris:
            e1, e2 = b - a, c - a
            pvec = np.cross(d, e2)
            det = pvec @ e1
            ok = np.abs(det) > 1e-12
            inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
            tvec = o - a
            u = np.sum(tvec * pvec, axis=1) * inv
            qvec = np.cross(tvec, e1)
            v = np.sum(d * qvec, axis=1) * inv
            t = (qvec @ e2) * inv
            hit |= ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-6)
        out[s:s + chunk] = hit
    return out


def rot_y(deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def sky_lookup(sky, d, rotation=0.0, intensity=1.0):
    """Cycles' Linear lookup of the sky for world directions d (N x 3): bilinear between pixel
    centres (i + 1/2), repeating in x and in y, after turning d back by the rotation."""
    h, w = sky.shape[:2]
    d = d @ rot_y(-rotation).T
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    x = w * (0.5 + np.arctan2(d[:, 2], d[:, 0]) / (2 * np.pi)) - 0.5
    y = h * np.arccos(np.clip(d[:, 1], -1.0, 1.0)) / np.pi - 0.5
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    def px(i, j):
        return sky[j % h, i % w]
    return intensity * ((1 - fy) * ((1 - fx) * px(x0, y0) + fx * px(x0 + 1, y0))
                        + fy * ((1 - fx) * px(x0, y0 + 1) + fx * px(x0 + 1, y0 + 1)))


def image_directions(sky, sub, rows=None, cols=None):
    """Directions and solid angles of sub x sub positions in each image pixel (image frame)."""
    h, w = sky.shape[:2]
    rows = np.arange(h) if rows is None else rows
    cols = np.arange(w) if cols is None else cols
    o = (np.arange(sub) + 0.5) / sub
    y = (rows[:, None] + o[None, :]).ravel()
    x = (cols[:, None] + o[None, :]).ravel()
    yy, xx = np.meshgrid(y, x, indexing="ij")
    phi = 2 * np.pi * (xx / w - 0.5)
    e = np.pi * (0.5 - yy / h)
    d = np.stack([np.cos(e) * np.cos(phi), np.sin(e), np.cos(e) * np.sin(phi)], axis=-1).reshape(-1, 3)
    domega = (np.cos(e) * (2 * np.pi / (w * sub)) * (np.pi / (h * sub))).ravel()
    return d, domega


def direct_irradiance(sky, p, n, tris, rotation, sun_box):
    """E at p (normal n) from the sky with visibility: sum of L cos dOmega."""
    h, w = sky.shape[:2]
    r0, r1, c0, c1 = sun_box
    mask = np.ones((h, w), dtype=bool)
    mask[r0:r1, c0:c1] = False
    total = 0.0
    for rows, cols, sub in ((np.arange(h), np.arange(w), 2), (np.arange(r0, r1), np.arange(c0, c1), 8)):
        d_img, domega = image_directions(sky, sub, rows, cols)
        if sub == 2:
            keep = np.repeat(np.repeat(mask, 2, axis=0), 2, axis=1).ravel()
            d_img, domega = d_img[keep], domega[keep]
        d = d_img @ rot_y(rotation).T
        cos = d @ n
        up = cos > 0
        d, domega, cos = d[up], domega[up], cos[up]
        visible = ~hits(p + 1e-5 * n, d, tris)
        total = total + (sky_lookup(sky, d, rotation) * (cos * domega * visible)[:, None]).sum(axis=0)
    return total


def texel_point(tris, uvs, normals, texel, res):
    """The 3D point and normal of a lightmap texel's centre (glTF v runs down the image)."""
    uv = (np.array(texel, dtype=np.float64) + 0.5) / res
    for k, (t, q) in enumerate(zip(tris, uvs)):
        m = np.array([[q[1, 0] - q[0, 0], q[2, 0] - q[0, 0]], [q[1, 1] - q[0, 1], q[2, 1] - q[0, 1]]])
        if abs(np.linalg.det(m)) < 1e-14:
            continue
        b1, b2 = np.linalg.solve(m, uv - q[0])
        if b1 >= 0 and b2 >= 0 and b1 + b2 <= 1:
            return t[0] + b1 * (t[1] - t[0]) + b2 * (t[2] - t[0]), normals[k], k
    return None


def texel_of_point(tris, uvs, point, res):
    for t, q in zip(tris, uvs):
        e1, e2 = t[1] - t[0], t[2] - t[0]
        n = np.cross(e1, e2)
        if abs((point - t[0]) @ n) > 1e-6 * np.linalg.norm(n):
            continue
        m = np.stack([e1, e2], axis=1)
        b, *_ = np.linalg.lstsq(m, point - t[0], rcond=None)
        if b[0] >= 0 and b[1] >= 0 and b.sum() <= 1:
            uv = q[0] + b[0] * (q[1] - q[0]) + b[1] * (q[2] - q[0])
            return tuple(np.floor(uv * res).astype(int))
    return None


# ---- checks ----------------------------------------------------------------------------------
def check_render(name, scene, render_path, sky, rotation):
    tris, uvs, normals, names, camera = scene
    img = read_exr(render_path)
    h, w = img.shape[:2]
    t, r, yfov, aspect = camera
    sub = 4
    o = (np.arange(sub) + 0.5) / sub
    ys = (np.arange(h)[:, None] + o[None, :]).ravel()
    xs = (np.arange(w)[:, None] + o[None, :]).ravel()
    yy, xx = np.meshgrid(ys, xs, indexing="ij")
    tan = math.tan(yfov / 2)
    cam_d = np.stack([(2 * xx / w - 1) * tan * aspect, (1 - 2 * yy / h) * tan, -np.ones_like(xx)], axis=-1).reshape(-1, 3)
    d = cam_d @ r.T
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    miss = ~hits(t, d, tris)
    expected = sky_lookup(sky, d, rotation).reshape(h, sub, w, sub, 3).mean(axis=(1, 3))
    sky_only = miss.reshape(h, sub, w, sub).all(axis=(1, 3))
    n = int(sky_only.sum())
    got, want = img[sky_only], expected[sky_only]
    rel = np.sqrt(np.mean((got - want) ** 2)) / np.mean(want)
    print("%s render: %d pixels see only sky; mean Cycles %s, expected %s (ratio %s); per-pixel relative RMS %.2f%%"
          % (name, n, np.round(got.mean(axis=0), 4), np.round(want.mean(axis=0), 4),
             np.round(got.mean(axis=0) / want.mean(axis=0), 4), 100 * rel))
    return got.mean(axis=0) / want.mean(axis=0)


def check_texels(name, scene, direct_path, sky, rotation, points, sun_box, total_path=None):
    tris, uvs, normals, names, camera = scene
    direct = read_exr(direct_path)
    total = read_exr(total_path) if total_path else None
    res = direct.shape[0]
    out = []
    for label, point in points:
        texel = texel_of_point(tris, uvs, np.array(point, dtype=np.float64), res)
        p, n, k = texel_point(tris, uvs, normals, texel, res)
        e = direct_irradiance(sky, p, n, tris, rotation, sun_box) / math.pi
        x, y = texel
        got = direct[y, x]
        # Cycles' per-texel noise: compare with the 3 x 3 neighbourhood's spread too.
        print("%s %-22s texel (%3d, %3d) at %s: Cycles direct %s, integrated E/pi %s (ratio %s)%s"
              % (name, label, x, y, np.round(p, 3), np.round(got, 4), np.round(e, 4), np.round(got / e, 3),
                 "" if total is None else ", total %s" % np.round(total[y, x], 4)))
        out.append(got / e)
    return out


def check_roof(scene, direct_path, total_path, mask_path, sky, rotation):
    tris, uvs, normals, names, camera = scene
    direct, total, mask = read_exr(direct_path), read_exr(total_path), read_exr(mask_path)[..., 0]
    res = direct.shape[0]
    top = np.array([i for i, (nm, t, n) in enumerate(zip(names, tris, normals))
                    if nm == "Exterior" and n[1] > 0.99 and abs(t[0, 1] - t[:, 1].max()) < 1e-6])
    yy, xx = np.mgrid[0:res, 0:res]
    uv = np.stack([(xx + 0.5) / res, (yy + 0.5) / res], axis=-1)
    roof = np.zeros((res, res), dtype=bool)
    for k in top:
        q = uvs[k]
        m = np.array([[q[1, 0] - q[0, 0], q[2, 0] - q[0, 0]], [q[1, 1] - q[0, 1], q[2, 1] - q[0, 1]]])
        b = (uv - q[0]) @ np.linalg.inv(m).T
        roof |= (b[..., 0] >= 0) & (b[..., 1] >= 0) & (b.sum(axis=-1) <= 1)
    roof &= mask > 0.5
    d, domega = image_directions(sky, 4)
    d = d @ rot_y(rotation).T
    cos = np.clip(d[:, 1], 0, None)
    e = (sky_lookup(sky, d, rotation) * (cos * domega)[:, None]).sum(axis=0) / math.pi
    print("window_room roof: %d texels; mean direct %s, mean total %s, open-sky E/pi %s (ratios %s, %s); texel spread (direct) %.2f%% RMS"
          % (roof.sum(), np.round(direct[roof].mean(axis=0), 4), np.round(total[roof].mean(axis=0), 4), np.round(e, 4),
             np.round(direct[roof].mean(axis=0) / e, 4), np.round(total[roof].mean(axis=0) / e, 4),
             100 * np.sqrt(np.mean((direct[roof] - e) ** 2)) / e.mean()))
    return direct[roof].mean(axis=0) / e


def main():
    sky = read_exr(os.path.join(ROOT, "scenes", "skies", "afternoon.exr"))
    sun_box = (62, 96, 338, 380)  # rows, cols around the sun (centre 78.2, 358.4; glow beyond is smooth)
    spp = sys.argv[1] if len(sys.argv) > 1 else "4096"
    cornell = load_gltf(os.path.join(ROOT, "..", "shared", "reference", "cornell_sky.gltf"))
    room = load_gltf(os.path.join(ROOT, "scenes", "window_room.gltf"))
    ref = lambda f: os.path.join(REF, f)
    check_render("cornell_sky_image", cornell, ref("cornell_sky_image_render_%sspp.exr" % spp), sky, 0.0)
    check_render("window_room", room, ref("window_room_render_%sspp.exr" % spp), sky, -45.0)
    check_roof(room, ref("window_room_lightmap_direct_%sspp.exr" % spp), ref("window_room_lightmap_%sspp.exr" % spp),
               ref("window_room_lightmap_mask.exr"), sky, -45.0)
    cornell_points = [("floor, sunlit", (0.15, 0.0, -0.08)), ("floor, back right", (0.45, 0.0, -0.5)),
                      ("back wall", (0.2, 0.45, -0.5592)), ("red wall", (0.0, 0.45, -0.3)),
                      ("green wall", (0.556, 0.45, -0.3))]
    check_texels("cornell_sky_image", cornell, ref("cornell_sky_image_lightmap_direct_%sspp.exr" % spp), sky, 0.0,
                 cornell_points, sun_box)
    room_points = [("floor, sunlit", (2.6, 0.0, -1.6)), ("floor, shade", (1.0, 0.0, -2.0)),
                   ("table top", (3.6, 0.75, -2.7)), ("back wall", (2.5, 1.4, -4.0))]
    check_texels("window_room", room, ref("window_room_lightmap_direct_%sspp.exr" % spp), sky, -45.0,
                 room_points, sun_box)
    # Rotation 90 (total lightmap only): the sun comes from +X over the green wall and lights the
    # red wall's upper part; at -90 it would light the green wall instead.
    total90 = read_exr(ref("cornell_sky_image_rot90_lightmap_%sspp.exr" % spp))
    tris, uvs, normals, names, camera = cornell
    for label, point in (("red wall", (0.0, 0.45, -0.3)), ("green wall", (0.556, 0.45, -0.3))):
        texel = texel_of_point(tris, uvs, np.array(point), total90.shape[0])
        p, n, k = texel_point(tris, uvs, normals, texel, total90.shape[0])
        e90 = direct_irradiance(sky, p, n, tris, 90.0, sun_box) / math.pi
        em90 = direct_irradiance(sky, p, n, tris, -90.0, sun_box) / math.pi
        print("cornell_sky_image rot90 %-10s texel (%3d, %3d): Cycles total %s; integrated direct at +90 %s, at -90 %s"
              % (label, texel[0], texel[1], np.round(total90[texel[1], texel[0]], 4), np.round(e90, 4), np.round(em90, 4)))


if __name__ == "__main__":
    main()
