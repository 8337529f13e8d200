# Blender's Lightmap Pack on a glTF scene, the peer of voxlight's generated lightmap UVs
# (docs/atlas.md, "Before this: Lightmap Pack and the charts by projection"). Run:
#   blender -b --factory-startup --python tools/bench/blender_lightmap_pack.py -- SCENE.gltf|glb MARGIN_TEXELS RESOLUTION
# Packs every mesh into one new UV layer together (Lightmap Pack's "pack in one"), with a
# margin of MARGIN_TEXELS at RESOLUTION texels (PREF_MARGIN_DIV = margin / resolution), and
# prints one JSON line: faces, seconds, the UV polygons' area share of the unit square, and
# the area stretch (3D area / UV area, each over its scene total; the largest over faces of
# at least a millionth of the scene's area) max and mean.
import bpy, json, sys, time
import numpy

if not hasattr(numpy, "bool"):  # Blender 3.4's glTF importer, with Debian's numpy
    numpy.bool = bool

args = sys.argv[sys.argv.index("--") + 1:]
path, margin, resolution = args[0], float(args[1]), int(args[2])
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=path)
meshes = [o for o in bpy.context.scene.objects if o.type == 'MESH']
for o in bpy.context.scene.objects:
    o.select_set(o in meshes)
bpy.context.view_layer.objects.active = meshes[0]
start = time.time()
bpy.ops.object.mode_set(mode='EDIT')
bpy.ops.mesh.select_all(action='SELECT')
bpy.ops.uv.lightmap_pack(PREF_CONTEXT='ALL_FACES', PREF_PACK_IN_ONE=True, PREF_NEW_UVLAYER=True,
                         PREF_BOX_DIV=12, PREF_MARGIN_DIV=margin / resolution)
bpy.ops.object.mode_set(mode='OBJECT')
seconds = time.time() - start

# Each mesh once: objects that share a mesh (instances) share its UVs.
faces, uv_total, area_total, pairs, seen = 0, 0.0, 0.0, [], set()
for o in meshes:
    m = o.data
    if m.name in seen:
        continue
    seen.add(m.name)
    layer = m.uv_layers.active.data  # Lightmap Pack writes the active layer (and keeps a copy of the old one)
    world = o.matrix_world
    for poly in m.polygons:
        uv = [layer[i].uv for i in poly.loop_indices]
        a = 0.0
        for k in range(1, len(uv) - 1):
            a += abs((uv[k].x - uv[0].x) * (uv[k + 1].y - uv[0].y) - (uv[k].y - uv[0].y) * (uv[k + 1].x - uv[0].x)) / 2
        p = [world @ m.vertices[v].co for v in poly.vertices]
        b = 0.0
        for k in range(1, len(p) - 1):
            b += (p[k] - p[0]).cross(p[k + 1] - p[0]).length / 2
        faces += 1
        uv_total += a
        area_total += b
        pairs.append((a, b))
kept = [(a, b) for a, b in pairs if a > 0 and b > 1e-6 * area_total]
ratios = [(b / area_total) / (a / uv_total) for a, b in kept]
weights = [b for a, b in kept]
mean = sum(r * w for r, w in zip(ratios, weights)) / sum(weights) if weights else 1.0
print("LIGHTMAP_PACK " + json.dumps({"scene": path, "faces": faces, "seconds": seconds, "uv_area": uv_total,
                                     "stretch_max": max(ratios) if ratios else 1.0, "stretch_mean": mean}))
