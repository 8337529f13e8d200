# Builds scenes/window_room.gltf (+ window_room.bin): a room lit only through one window, for
# the image-sky references in tests/reference/sky/. Headless Blender (3.4.1 here):
#
#   nice -n 19 blender -b --factory-startup --python-exit-code 1 \
#       --python scenes/skies/make_window_room.py [-- --out scenes/window_room.gltf]
#
# Geometry, in glTF coordinates (metres, +Y up; Blender's (x, y, z) = glTF (x, -z, y)):
# - interior 5 x 2.8 x 4 m: x in [0, 5], y in [0, 2.8], z in [-4, 0];
# - a closed shell 0.15 m thick around it (outer box x in [-0.15, 5.15], y in [-0.15, 2.95],
#   z in [-4.15, 0.15]) with one window, a real hole through the z = 0 wall: x in [1.3, 3.1],
#   y in [0.9, 2.2] (1.8 x 1.3 m), looking out along +Z, with its four reveals. The shell is
#   its inner faces (normals into the room: Floor, Ceiling, Walls, the reveals in Walls) and
#   its outer faces (Exterior, normals out), so walls, floor and ceiling are solid slabs
#   with no faces inside one another;
# - a table block, x in [3.3, 4.5], y in [0, 0.75], z in [-2.9, -2.1], and a cabinet block,
#   x in [0.4, 1.4], y in [0, 1.9], z in [-3.97, -3.47] (3 cm off the back wall); both stand
#   on the floor and, like the Cornell boxes' blocks, have no bottom face;
# - Lambert materials (Principled, specular 0, roughness 1, not metallic; cycles_bake.py
#   turns them into Diffuse BSDFs): walls and exterior 0.7 grey, floor (0.55, 0.44, 0.33),
#   ceiling 0.8, table (0.45, 0.3, 0.18), cabinet (0.35, 0.5, 0.6);
# - one perspective camera (yfov 65 degrees, aspect 1) at (0.4, 1.5, -3.3) looking at
#   (3.0, 0.4, -1.2): the window wall at an angle and the floor where the sun falls with the
#   sky of the references (afternoon.exr turned by -45 degrees: the sun, at azimuth
#   atan2(d.z, d.x) = 117 degrees and 35 degrees up, d = (-0.372, 0.574, 0.730), comes in
#   through the window from +Z and -X and lights a patch of floor about x in [1.9, 4.5],
#   z in [-2.8, -1.1], part of it on the table);
# - no lights.
# UVs: TEXCOORD_0 from Smart UV Project (unused: no textures); TEXCOORD_1 one shared lightmap
# atlas over every mesh: Smart UV Project over all meshes together (angle limit 30 degrees,
# island margin 0.02, no area weighting, not scaled to bounds), so every face has the same
# texel density (251 texels per m^2 at 256^2, 6.3 cm texels) and coplanar neighbours share an
# island. Checked here at 256^2: no two faces overlap and charts are at least one empty texel
# apart (each texel any of whose 4 x 4 sub-positions a chart touches counts as the chart's).
import math
import os
import sys

import bmesh
import bpy
import numpy
from mathutils import Vector

if not hasattr(numpy, "bool"):
    numpy.bool = bool

HERE = os.path.dirname(os.path.abspath(__file__))
T = 0.15
X1, Y1, Z0 = 5.0, 2.8, -4.0  # interior: x in [0, X1], y in [0, Y1], z in [Z0, 0]
WIN_X, WIN_Y = (1.3, 3.1), (0.9, 2.2)


def blender(p):
    """glTF point -> Blender point."""
    return Vector((p[0], -p[2], p[1]))


def rect(axis, c, r0, r1, sign):
    """An axis-aligned rectangle at glTF coordinate[axis] = c spanning r0 x r1 over the other
    two axes (in x, y, z order), with its normal along sign * axis. Returns 4 glTF corners."""
    u, v = [a for a in range(3) if a != axis]
    corners = []
    for a, b in ((r0[0], r1[0]), (r0[1], r1[0]), (r0[1], r1[1]), (r0[0], r1[1])):
        p = [0.0, 0.0, 0.0]
        p[axis], p[u], p[v] = c, a, b
        corners.append(p)
    e0 = numpy.subtract(corners[1], corners[0])
    e1 = numpy.subtract(corners[2], corners[0])
    if numpy.cross(e0, e1)[axis] * sign < 0:
        corners.reverse()
    return corners


def box(x, y, z):
    """A block's five visible faces (no bottom), normals out."""
    return [rect(1, y[1], x, z, +1),
            rect(0, x[0], y, z, -1), rect(0, x[1], y, z, +1),
            rect(2, z[0], x, y, -1), rect(2, z[1], x, y, +1)]


def material(name, color):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    p = m.node_tree.nodes["Principled BSDF"]
    p.inputs["Base Color"].default_value = (color[0], color[1], color[2], 1.0)
    p.inputs["Metallic"].default_value = 0.0
    p.inputs["Specular"].default_value = 0.0
    p.inputs["Roughness"].default_value = 1.0
    return m


def mesh_object(name, quads, mat):
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    for q in quads:
        bm.faces.new([bm.verts.new(blender(p)) for p in q])
    bmesh.ops.remove_doubles(bm, verts=bm.verts, dist=1e-6)
    bm.to_mesh(mesh)
    bm.free()
    mesh.materials.append(mat)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def build():
    walls_m = material("Walls", (0.7, 0.7, 0.7))
    floor_m = material("Floor", (0.55, 0.44, 0.33))
    ceiling_m = material("Ceiling", (0.8, 0.8, 0.8))
    table_m = material("Table", (0.45, 0.3, 0.18))
    cabinet_m = material("Cabinet", (0.35, 0.5, 0.6))
    x, y, z = (0.0, X1), (0.0, Y1), (Z0, 0.0)
    (wx0, wx1), (wy0, wy1) = WIN_X, WIN_Y
    mesh_object("Floor", [rect(1, 0.0, x, z, +1)], floor_m)
    mesh_object("Ceiling", [rect(1, Y1, x, z, -1)], ceiling_m)
    walls = [rect(0, 0.0, y, z, +1), rect(0, X1, y, z, -1), rect(2, Z0, x, y, +1),
             # the window wall (z = 0, facing -Z into the room) around the hole
             rect(2, 0.0, x, (0.0, wy0), -1), rect(2, 0.0, x, (wy1, Y1), -1),
             rect(2, 0.0, (0.0, wx0), (wy0, wy1), -1), rect(2, 0.0, (wx1, X1), (wy0, wy1), -1),
             # the reveals, facing into the opening
             rect(1, wy0, WIN_X, (0.0, T), +1), rect(1, wy1, WIN_X, (0.0, T), -1),
             rect(0, wx0, WIN_Y, (0.0, T), +1), rect(0, wx1, WIN_Y, (0.0, T), -1)]
    mesh_object("Walls", walls, walls_m)
    ox, oy, oz = (-T, X1 + T), (-T, Y1 + T), (Z0 - T, T)
    exterior = [rect(1, oy[0], ox, oz, -1), rect(1, oy[1], ox, oz, +1),
                rect(0, ox[0], oy, oz, -1), rect(0, ox[1], oy, oz, +1),
                rect(2, oz[0], ox, oy, -1),
                rect(2, T, ox, (oy[0], wy0), +1), rect(2, T, ox, (wy1, oy[1]), +1),
                rect(2, T, (ox[0], wx0), (wy0, wy1), +1), rect(2, T, (wx1, ox[1]), (wy0, wy1), +1)]
    mesh_object("Exterior", exterior, walls_m)
    mesh_object("Table", box((3.3, 4.5), (0.0, 0.75), (-2.9, -2.1)), table_m)
    mesh_object("Cabinet", box((0.4, 1.4), (0.0, 1.9), (-3.97, -3.47)), cabinet_m)

    scene = bpy.context.scene
    scene.render.resolution_x = scene.render.resolution_y = 256
    cam_data = bpy.data.cameras.new("Camera")
    cam_data.sensor_fit = "VERTICAL"
    cam_data.angle_y = math.radians(65.0)
    cam_data.clip_start, cam_data.clip_end = 0.01, 100.0
    cam = bpy.data.objects.new("Camera", cam_data)
    scene.collection.objects.link(cam)
    eye, target = blender((0.4, 1.5, -3.3)), blender((3.0, 0.4, -1.2))
    cam.location = eye
    cam.rotation_mode = "QUATERNION"
    cam.rotation_quaternion = (target - eye).to_track_quat("-Z", "Y")
    scene.camera = cam


def lightmap_uvs(margin):
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    for o in meshes:
        o.data.uv_layers.new(name="UVMap")
        o.data.uv_layers.new(name="Lightmap")
    bpy.ops.object.select_all(action="DESELECT")
    for o in meshes:
        o.select_set(True)
    bpy.context.view_layer.objects.active = meshes[0]
    for index, pack in ((0, False), (1, True)):
        for o in meshes:
            o.data.uv_layers.active_index = index
        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_all(action="SELECT")
        if pack:
            bpy.ops.uv.smart_project(angle_limit=math.radians(30.0), island_margin=margin, area_weight=0.0,
                                     correct_aspect=True, scale_to_bounds=False)
        else:
            bpy.ops.uv.smart_project(island_margin=0.02)
        bpy.ops.object.mode_set(mode="OBJECT")
    for o in meshes:
        o.data.uv_layers.active_index = 0
        o.data.uv_layers[0].active_render = True


def check_atlas(res):
    """Rasterises every TEXCOORD_1 triangle on a 4 x 4 grid in each texel of a res^2 atlas: a
    texel touched by a chart (a UV island) must have no texel of another chart among its
    eight neighbours (at least one empty texel between charts), and no two faces may claim
    the same point. Returns (share of texels touched, texels per m^2 min and max)."""
    from bpy_extras import mesh_utils
    sub = 4
    owner = numpy.full((res * sub, res * sub), -1, dtype=numpy.int64)
    face_owner = numpy.full((res * sub, res * sub), -1, dtype=numpy.int64)
    chart, face_id, densities = 0, 0, []
    for o in bpy.context.scene.objects:
        if o.type != "MESH":
            continue
        mesh = o.data
        mesh.uv_layers.active_index = 1
        islands = mesh_utils.mesh_linked_uv_islands(mesh)
        mesh.uv_layers.active_index = 0
        island_of = {f: i for i, faces in enumerate(islands) for f in faces}
        uv = mesh.uv_layers["Lightmap"].data
        for poly in mesh.polygons:
            pts = numpy.array([uv[i].uv[:] for i in poly.loop_indices]) * res * sub
            uv_area = 0.0
            for k in range(1, len(pts) - 1):
                a, b, c = pts[0], pts[k], pts[k + 1]
                uv_area += abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / 2
                lo = numpy.floor(numpy.minimum(numpy.minimum(a, b), c)).astype(int)
                hi = numpy.ceil(numpy.maximum(numpy.maximum(a, b), c)).astype(int)
                gy, gx = numpy.mgrid[lo[1]:hi[1], lo[0]:hi[0]] + 0.5

                def edge(p, q):
                    return (q[0] - p[0]) * (gy - p[1]) - (q[1] - p[1]) * (gx - p[0])
                e0, e1, e2 = edge(a, b), edge(b, c), edge(c, a)
                inside = ((e0 > 0) & (e1 > 0) & (e2 > 0)) | ((e0 < 0) & (e1 < 0) & (e2 < 0))
                iy, ix = numpy.nonzero(inside)
                iy, ix = iy + lo[1], ix + lo[0]
                clash = face_owner[iy, ix]
                if numpy.any((clash >= 0) & (clash != face_id)):
                    raise SystemExit("make_window_room.py: lightmap faces overlap (%s face %d)" % (o.name, poly.index))
                face_owner[iy, ix] = face_id
                owner[iy, ix] = chart + island_of[poly.index]
            densities.append(uv_area / sub ** 2 / poly.area)
            face_id += 1
        chart += len(islands)
    texel = owner.reshape(res, sub, res, sub).max(axis=(1, 3))  # a chart touching the texel
    # (max picks one; a texel touched by two charts is caught below by the neighbours' test)
    touched = owner.reshape(res, sub, res, sub).transpose(0, 2, 1, 3).reshape(res, res, sub * sub)
    for y in range(res):
        for x in range(res):
            here = set(touched[y, x][touched[y, x] >= 0].tolist())
            if not here:
                continue
            near = touched[max(0, y - 1):y + 2, max(0, x - 1):x + 2].ravel()
            if len(here) > 1 or any(c >= 0 and c not in here for c in near.tolist()):
                raise SystemExit("make_window_room.py: charts closer than one empty texel at (%d, %d)" % (x, y))
    return (texel >= 0).mean(), min(densities), max(densities)


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    out = argv[argv.index("--out") + 1] if "--out" in argv else os.path.join(HERE, "..", "window_room.gltf")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    build()
    lightmap_uvs(0.02)
    covered, dmin, dmax = check_atlas(256)
    print("window_room: atlas covers %.1f%% of 256^2 texels, %.0f..%.0f texels per m^2, no overlaps"
          % (100 * covered, dmin, dmax))
    bpy.ops.export_scene.gltf(filepath=os.path.abspath(out), export_format="GLTF_SEPARATE", export_yup=True,
                              export_cameras=True, export_lights=False, export_texcoords=True,
                              export_normals=True, export_materials="EXPORT", export_apply=True,
                              export_extras=False, use_selection=False)


main()
