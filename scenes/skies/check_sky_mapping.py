# Measures how Cycles (through tools/bench/cycles_bake.py's world) maps a glTF direction to an
# equirectangular sky image, and checks the formula and the rotation convention documented
# in tests/reference/sky/README.md. Headless Blender (3.4.1 here), with oiiotool on the PATH:
#
#   nice -n 19 blender -b --factory-startup --python-exit-code 1 \
#       --python scenes/skies/check_sky_mapping.py -- [--sky scenes/skies/afternoon.exr] [--work DIR]
#
# 1. A 512 x 256 float EXR whose pixel (column i, row j from the top of the file) holds
#    R = i + 1/2, G = j + 1/2 -- linear in the image coordinates, so with Linear (bilinear)
#    interpolation the value looked up IS the continuous coordinate (x, y) Cycles sampled.
#    A glTF file of cameras (no meshes) looking along known glTF directions goes through
#    Blender's glTF importer, as the bench's scenes do; each camera renders a 3 x 3 image
#    with a 1e-5 rad field of view, and its centre pixel gives (x, y) for that direction.
#    That is compared with
#        x = W (1/2 + atan2(d.z, d.x) / (2 pi)),  y = H acos(d.y) / pi
#    at rotations 0, 90 and -37.5 degrees (L(d) = L_image(R_y(-theta) d)), with Linear and
#    Closest interpolation (Closest returns floor(x) + 1/2: pixel i covers [i, i + 1)); and
#    Linear next to the seam (x wraps: columns W - 1 and 0 blend) and the poles (y wraps
#    too: rows 0 and H - 1 blend within half a pixel of either pole).
# 2. The afternoon sky at rotation 90: a camera aimed where the formula puts the sun
#    (R_y(90) times the sun's image direction) sees the disc centred; one aimed at the
#    unrotated sun direction does not see it.
# Prints the errors and exits non-zero when one is over 0.02 pixel (or the sun is off by
# more than 0.5 pixel of the 64 x 64 check image).
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy

if not hasattr(numpy, "bool"):
    numpy.bool = bool

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools", "bench"))
sys.path.insert(0, HERE)
import cycles_bake  # noqa: E402  (the world the references use)

W, H = 512, 256


def formula(d):
    d = numpy.asarray(d, dtype=numpy.float64)
    d = d / numpy.linalg.norm(d)
    return W * (0.5 + math.atan2(d[2], d[0]) / (2.0 * math.pi)), H * math.acos(max(-1.0, min(1.0, d[1]))) / math.pi


def rot_y(deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return numpy.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])  # right-handed about +Y


def quaternion_looking(d):
    """glTF node rotation (x, y, z, w) turning the camera's -Z onto d."""
    d = numpy.asarray(d, dtype=numpy.float64)
    d = d / numpy.linalg.norm(d)
    up0 = numpy.array([0.0, 1.0, 0.0]) if abs(d[1]) < 0.9 else numpy.array([1.0, 0.0, 0.0])
    right = numpy.cross(d, up0)
    right /= numpy.linalg.norm(right)
    up = numpy.cross(right, d)
    m = numpy.stack([right, up, -d], axis=1)
    assert abs(numpy.linalg.det(m) - 1.0) < 1e-9
    w = math.sqrt(max(0.0, 1.0 + m[0, 0] + m[1, 1] + m[2, 2])) / 2.0
    if w > 1e-3:
        return [(m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w), (m[1, 0] - m[0, 1]) / (4 * w), w]
    i = int(numpy.argmax(numpy.diag(m)))
    j, k = (i + 1) % 3, (i + 2) % 3
    r = math.sqrt(max(0.0, 1.0 + m[i, i] - m[j, j] - m[k, k]))
    q = [0.0, 0.0, 0.0, 0.0]
    q[i] = r / 2.0
    q[j] = (m[j, i] + m[i, j]) / (2 * r)
    q[k] = (m[k, i] + m[i, k]) / (2 * r)
    q[3] = (m[k, j] - m[j, k]) / (2 * r)
    return q


def write_exr(path, image):
    h, w = image.shape[:2]
    pfm = path + ".pfm"
    with open(pfm, "wb") as out:
        out.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        out.write(numpy.ascontiguousarray(numpy.flipud(image)).astype("<f4").tobytes())
    subprocess.run(["oiiotool", pfm, "-d", "float", "--compression", "zip", "-o", path], check=True)
    os.remove(pfm)


def write_cameras(path, directions, yfov):
    gltf = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": list(range(len(directions)))}],
            "nodes": [], "cameras": []}
    for i, d in enumerate(directions):
        gltf["cameras"].append({"type": "perspective", "perspective": {"yfov": yfov, "aspectRatio": 1.0,
                                                                       "znear": 0.01, "zfar": 100.0}})
        gltf["nodes"].append({"name": "cam%03d" % i, "camera": i, "rotation": quaternion_looking(d)})
    with open(path, "w") as out:
        json.dump(gltf, out)


class Args:
    pass


def setup(scene, sky_image, rotation, interpolation, res, spp):
    args = Args()
    args.sky, args.sky_image, args.sky_rotation = None, sky_image, rotation
    args.sky_intensity, args.sky_interpolation = 1.0, interpolation
    args.spp, args.seed = spp, 1
    cycles_bake.configure(scene, args)  # the references' settings and world
    scene.render.resolution_x = scene.render.resolution_y = res
    scene.render.resolution_percentage = 100


def render(scene, camera, work):
    scene.camera = camera
    bpy.ops.render.render(write_still=False)
    path = os.path.join(work, "r.exr")
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    image = bpy.data.images.load(path, check_existing=False)
    pixels = numpy.empty(len(image.pixels), dtype=numpy.float32)
    image.pixels.foreach_get(pixels)
    out = numpy.flipud(pixels.reshape(image.size[1], image.size[0], 4)[:, :, :3]).astype(numpy.float64)
    bpy.data.images.remove(image)
    return out  # rows from the top


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    sky = os.path.join(HERE, "afternoon.exr")
    work = None
    for i, a in enumerate(argv):
        if a == "--sky":
            sky = argv[i + 1]
        if a == "--work":
            work = argv[i + 1]
    work = work or tempfile.mkdtemp(prefix="sky_mapping_")
    os.makedirs(work, exist_ok=True)
    ok = True

    # 1. The coordinate image.
    ys, xs = numpy.mgrid[0:H, 0:W].astype(numpy.float64)
    coord = numpy.stack([xs + 0.5, ys + 0.5, numpy.zeros_like(xs)], axis=-1)
    coord_path = os.path.join(work, "coord.exr")
    write_exr(coord_path, coord)
    rng = numpy.random.default_rng(12345)
    directions = [(0, 0, -1), (1, 0, 0), (0, 0, 1), (-1, 0, 0.02), (0, 1, 0.05), (0.03, -1, 0.02),
                  (1, 1, 1), (-0.3, 0.7, -1), (0.8, -0.4, 0.3)]
    while len(directions) < 40:
        d = rng.normal(size=3)
        directions.append(tuple(d / numpy.linalg.norm(d)))
    cameras_path = os.path.join(work, "cameras.gltf")
    write_cameras(cameras_path, directions, 1e-5)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=cameras_path)
    scene = bpy.context.scene
    cams = sorted((o for o in scene.objects if o.type == "CAMERA"), key=lambda o: o.name)
    assert len(cams) == len(directions), [o.name for o in cams]
    for rotation, interpolation in ((0.0, "Linear"), (90.0, "Linear"), (-37.5, "Linear"), (0.0, "Closest")):
        setup(scene, coord_path, rotation, interpolation, 3, 4)
        worst, used = 0.0, 0
        for cam, d in zip(cams, directions):
            x, y = formula(rot_y(-rotation) @ numpy.asarray(d, dtype=numpy.float64))
            if interpolation == "Linear" and (min(x, W - x) < 1.0 or min(y, H - y) < 1.0):
                continue  # bilinear blends across the seam or clamps at a pole
            if interpolation == "Closest":
                if min(abs(x - round(x)), abs(y - round(y))) < 0.05:
                    continue  # on a pixel boundary
                x, y = math.floor(x) + 0.5, math.floor(y) + 0.5
            got = render(scene, cam, work)[1, 1]
            err = max(abs(got[0] - x), abs(got[1] - y))
            worst = max(worst, err)
            used += 1
            if err > 0.02:
                ok = False
                print("MISMATCH rot %g %s d=%s formula (%.3f, %.3f) Cycles (%.3f, %.3f)"
                      % (rotation, interpolation, numpy.round(d, 3), x, y, got[0], got[1]))
        print("rotation %6.1f %-7s: %d directions, worst |Cycles - formula| = %.4f px" % (rotation, interpolation, used, worst))

    # Linear at the seam and the poles: Cycles' environment lookup repeats in both axes, so
    # x wraps (column W - 1 blends with column 0) and so does y (within half a pixel of a pole
    # row 0 blends with row H - 1). Checked through the implied interpolation weight.
    edge = [(0.2, 100.3), (W - 0.2, 100.3), (300.3, 0.3), (300.3, H - 0.3)]
    edge_dirs = []
    for x, y in edge:
        phi, e = 2 * math.pi * (x / W - 0.5), math.pi * (0.5 - y / H)
        edge_dirs.append((math.cos(e) * math.cos(phi), math.sin(e), math.cos(e) * math.sin(phi)))
    write_cameras(cameras_path, edge_dirs, 1e-5)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=cameras_path)
    scene = bpy.context.scene
    cams = sorted((o for o in scene.objects if o.type == "CAMERA"), key=lambda o: o.name)
    setup(scene, coord_path, 0.0, "Linear", 3, 4)
    for cam, (x, y) in zip(cams, edge):
        got = render(scene, cam, work)[1, 1]
        for axis, (t, n) in enumerate(((x, W), (y, H))):
            i0 = math.floor(t - 0.5)
            f = t - 0.5 - i0
            a, b = (i0 % n) + 0.5, ((i0 + 1) % n) + 0.5  # the two pixel centres, wrapped
            implied = (got[axis] - a) / (b - a) if a != b else f
            print("edge (%.1f, %.1f) %s: Cycles %.3f = pixels %d and %d wrapped with weight %.4f (bilinear: %.4f)"
                  % (x, y, "xy"[axis], got[axis], a - 0.5, b - 0.5, implied, f))
            near_pole = axis == 0 and min(y, H - y) < 1.0  # x is ill-conditioned there
            if abs(implied - f) > 0.002 and not near_pole:
                ok = False

    # 2. The sun of the afternoon sky, rotated by 90 degrees.
    import make_sky  # the sun's place in the image
    sun_x, sun_y = make_sky.SUN_COLUMN, H * (0.5 - math.degrees(make_sky.SUN_ELEVATION) / 180.0)
    phi, e = 2 * math.pi * (sun_x / W - 0.5), math.pi * (0.5 - sun_y / H)
    sun = numpy.array([math.cos(e) * math.cos(phi), math.sin(e), math.cos(e) * math.sin(phi)])
    assert max(abs(a - b) for a, b in zip(formula(sun), (sun_x, sun_y))) < 1e-9
    rotated = rot_y(90.0) @ sun
    print("afternoon sun: image direction %s, at rotation 90 world direction %s" % (numpy.round(sun, 4), numpy.round(rotated, 4)))
    write_cameras(cameras_path, [rotated, sun], math.radians(20.0))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=cameras_path)
    scene = bpy.context.scene
    cams = sorted((o for o in scene.objects if o.type == "CAMERA"), key=lambda o: o.name)
    setup(scene, sky, 90.0, "Linear", 64, 16)
    for cam, what in zip(cams, ("aimed at R_y(90) sun", "aimed at the unrotated sun")):
        img = render(scene, cam, work)
        lum = img.sum(axis=-1)
        bright = lum > 100.0
        if bright.any():
            rows, cols = numpy.nonzero(bright)
            w = lum[bright]
            cy, cx = (rows + 0.5) @ w / w.sum(), (cols + 0.5) @ w / w.sum()
            print("%s: sun disc of %d pixels centred at (%.2f, %.2f) of 64 x 64, peak %s"
                  % (what, bright.sum(), cx, cy, numpy.round(img.reshape(-1, 3)[numpy.argmax(lum)], 1)))
            if what.startswith("aimed at R") and max(abs(cx - 32), abs(cy - 32)) > 0.5:
                ok = False
            if what.startswith("aimed at the"):
                ok = False
        else:
            print("%s: no sun (max luminance %.2f)" % (what, lum.max()))
            if what.startswith("aimed at R"):
                ok = False
    print("check_sky_mapping:", "OK" if ok else "FAILED")
    if not ok:
        sys.exit(1)


main()
