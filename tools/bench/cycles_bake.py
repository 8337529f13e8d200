# The Cycles peer of `voxlight bench`: bakes a glTF scene's shared lightmap atlas
# (TEXCOORD_1) with Cycles' DIFFUSE bake -- E/pi per texel, voxlight's lightmap convention --
# and renders its first camera, at one sample count, timing each. Headless:
#
#   blender -b --factory-startup --python-exit-code 1 --python tools/bench/cycles_bake.py -- \
#       --scene scene.gltf --out DIR --spp 64 [--lightmap-res 256] [--width 256 --height 256]
#       [--no-lightmap] [--no-image] [--seed 1] [--mask]
#       [--sky R,G,B | --sky-image PATH [--sky-rotation DEG] [--sky-intensity S]
#                                       [--sky-interpolation Linear|Closest]]
#       [--sun DX,DY,DZ --sun-irradiance E [--sun-angle DEG] [--sun-color R,G,B]]
#       [--one-sided-emitters] [--lambert-all]
#
# Writes DIR/lightmap.exr, DIR/lightmap_direct.exr, DIR/image.exr (linear float) and
# DIR/cycles.json (seconds of each bake and render, peak memory). Settings as the Cycles
# references in ../shared/reference: CPU, 64 bounces of every kind, no clamping, no light
# threshold, no adaptive sampling, no denoising, 1-pixel box filter, black world.
#
# Optional:
# --mask          also DIR/lightmap_mask.exr: 1 where Cycles' bake wrote a texel (its centre
#                 lies in a TEXCOORD_1 triangle of a baked mesh), 0 in padding. The total bake
#                 then starts from a -1 sentinel instead of Blender's clear; the lightmap's
#                 bytes are the same (padding is written as 0).
# --sky R,G,B     a uniform world of radiance (R, G, B) W/(m^2 sr): Background colour, strength 1.
# --sky-image P   an equirectangular HDR world (Environment Texture, read as Non-Color: the
#                 file's linear values are radiance in W/(m^2 sr), no colour transform), with
#                 world importance sampling ("Sample as light", MIS) on a map of the image's own
#                 resolution (MANUAL, sample_map_resolution = image width: width x width/2).
#                 In glTF coordinates (+Y up), direction d looks up the image at
#                   column (from the left edge) x = W * (1/2 + atan2(d.z, d.x) / (2 pi))
#                   row (from the top edge)     y = H * acos(d.y) / pi
#                 (continuous: pixel i spans [i, i + 1), its centre at i + 1/2; glTF -Z is
#                 x = W/4, +X the centre, +Z x = 3W/4, the seam at -X; measured, see
#                 tests/reference/sky/README.md).
# --sky-rotation DEG  turns the sky by DEG counterclockwise seen from above about +Y:
#                 L(d) = L_image(R_y(-DEG) d), R_y right-handed about glTF +Y (= Blender +Z): a
#                 Mapping node (Vector) of rotation (0, 0, -DEG) on the world's Generated
#                 coordinate. Default 0.
# --sky-intensity S   multiplies the image's radiance (Background strength). Default 1.
# --sky-interpolation  the Environment Texture's lookup: Linear (default: bilinear between
#                 pixel centres, wrapping across the seam in x) or Closest.
# --sun DX,DY,DZ  adds a sun (Blender SUN light): a directional light travelling along
#                 (DX, DY, DZ) in glTF coordinates (+Y up; need not be unit), as a job file's
#                 directional light "direction". The importer maps glTF (x, y, z) to Blender
#                 (x, -z, y); the sun's local -Z is turned onto that direction. Write a
#                 negative first component as --sun=-0.7,-0.55,-0.45 (argparse would read a
#                 separate "-0.7,..." as an option).
# --sun-irradiance E  its irradiance in W/m^2 on a surface facing it (Blender's sun strength,
#                 a job file's directional "intensity"). Needed with --sun.
# --sun-angle DEG  the sun disk's angular diameter in degrees (Blender's sun angle, a job
#                 file's "angle"). Default 0: a point-like sun, sharp shadows.
# --sun-color R,G,B  multiplies the irradiance per channel (a job file's "color"): the sun
#                 delivers (E R, E G, E B). Default 1,1,1.
#                 Checked (tests/reference/classroom/README.md): open quads facing +Y, +X, +Z,
#                 -X under suns along (0,-1,0) and (-0.7,-0.55,-0.45) bake E max(0, n.-d) R/pi
#                 per channel within 2e-5 on average (0.53 degree disk, 16 spp).
# --lambert-all   metallic and transmissive materials become Lambert too (their base colour),
#                 as voxlight's `materials lambert` makes them: the transport alone.
# --one-sided-emitters  emissive materials that glTF marks single-sided (no doubleSided:
#                 Blender's importer sets use_backface_culling) emit from their front face
#                 only, as glTF's culling and voxlight's emitters do; Cycles' emission is
#                 otherwise two-sided. Such a material becomes Lambert (Diffuse BSDF, roughness
#                 0, its base colour) on both sides plus its emission (colour x strength) where
#                 the ray meets the front (Geometry Backfacing = 0). Without the flag emitters
#                 are left as the importer made them (Principled, emitting from both sides).
#
# Lessons from Debian's Blender 3.4 (issue 6):
# - it has no denoiser but enables denoising by default: turn it off;
# - an indirect-only bake returns zero: bake direct+indirect and direct; the bench subtracts;
# - image.save_render writes float EXR (plain save writes sRGB-encoded values);
# - the glTF importer needs numpy.bool = bool with Debian's numpy;
# - the importer makes Principled BSDFs, whose diffuse lobe at roughness 1 is not Lambert
#   (its retro-reflection made the Cornell atlas's indirect light ~15% brighter than the
#   reference, made with Lambert walls): opaque, non-metallic, non-emissive materials get a
#   Diffuse BSDF (roughness 0: Lambert) with the same base colour, as voxlight models them.
import argparse
import json
import math
import os
import resource
import sys
import time

import numpy

if not hasattr(numpy, "bool"):
    numpy.bool = bool

import bpy


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="cycles_bake.py")
    p.add_argument("--scene", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--lightmap-res", type=int, default=256)
    p.add_argument("--width", type=int, default=256)
    p.add_argument("--height", type=int, default=256)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--no-lightmap", action="store_true")
    p.add_argument("--no-image", action="store_true")
    p.add_argument("--mask", action="store_true")
    sky = p.add_mutually_exclusive_group()
    sky.add_argument("--sky", type=rgb, default=None, metavar="R,G,B")
    sky.add_argument("--sky-image", default=None, metavar="PATH")
    p.add_argument("--sky-rotation", type=float, default=0.0, metavar="DEG")
    p.add_argument("--sky-intensity", type=float, default=1.0, metavar="S")
    p.add_argument("--sky-interpolation", choices=("Linear", "Closest"), default="Linear")
    p.add_argument("--sun", type=rgb, default=None, metavar="DX,DY,DZ")
    p.add_argument("--sun-irradiance", type=float, default=None, metavar="E")
    p.add_argument("--sun-angle", type=float, default=0.0, metavar="DEG")
    p.add_argument("--sun-color", type=rgb, default=(1.0, 1.0, 1.0), metavar="R,G,B")
    p.add_argument("--one-sided-emitters", action="store_true")
    p.add_argument("--lambert-all", action="store_true")
    args = p.parse_args(argv)
    if args.sun is None and (args.sun_irradiance is not None or args.sun_angle != 0.0
                             or args.sun_color != (1.0, 1.0, 1.0)):
        p.error("--sun-irradiance, --sun-angle and --sun-color need --sun")
    if args.sun is not None:
        if args.sun_irradiance is None or not args.sun_irradiance >= 0.0:
            p.error("--sun needs --sun-irradiance E >= 0")
        if not 0.0 <= args.sun_angle <= 180.0:
            p.error("--sun-angle must lie in [0, 180] degrees")
        if sum(v * v for v in args.sun) == 0.0:
            p.error("--sun direction is zero")
    if args.sky_image is None and (args.sky_rotation != 0.0 or args.sky_intensity != 1.0
                                   or args.sky_interpolation != "Linear"):
        p.error("--sky-rotation, --sky-intensity and --sky-interpolation need --sky-image")
    return args


def rgb(text):
    values = [float(v) for v in text.split(",")]
    if len(values) != 3:
        raise argparse.ArgumentTypeError("expected R,G,B")
    return tuple(values)


def set_if(obj, name, value):
    if hasattr(obj, name):
        setattr(obj, name, value)


def configure(scene, args):
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = args.spp
    c.seed = args.seed
    set_if(c, "use_adaptive_sampling", False)
    set_if(c, "use_denoising", False)
    set_if(c, "use_preview_denoising", False)
    for name in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
                 "volume_bounces", "transparent_max_bounces"):
        set_if(c, name, 64)
    set_if(c, "sample_clamp_direct", 0.0)
    set_if(c, "sample_clamp_indirect", 0.0)
    set_if(c, "light_sampling_threshold", 0.0)
    set_if(c, "pixel_filter_type", "BOX")
    set_if(c, "filter_width", 1.0)
    scene.view_settings.view_transform = "Standard"
    scene.render.threads_mode = "AUTO"
    scene.world = make_world(args)
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_depth = "32"
    settings.color_mode = "RGB"


def make_world(args):
    """The black world of the references, or the sky that --sky / --sky-image ask for."""
    sky = getattr(args, "sky", None)
    sky_image = getattr(args, "sky_image", None)
    world = bpy.data.worlds.new("sky" if sky or sky_image else "black")
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    background = nodes.get("Background")
    if sky_image is None:
        color, strength = ((0.0, 0.0, 0.0), 0.0) if sky is None else (sky, 1.0)
        background.inputs["Color"].default_value = (color[0], color[1], color[2], 1.0)
        background.inputs["Strength"].default_value = strength
        return world
    image = bpy.data.images.load(os.path.abspath(sky_image), check_existing=False)
    image.colorspace_settings.name = "Non-Color"  # the EXR's values as they are: radiance
    coordinates = nodes.new("ShaderNodeTexCoord")
    mapping = nodes.new("ShaderNodeMapping")
    mapping.vector_type = "VECTOR"
    # L(d) = L_image(R(-theta) d): the lookup turns the direction back by theta about
    # Blender's +Z, which is glTF's +Y.
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, -math.radians(getattr(args, "sky_rotation", 0.0)))
    texture = nodes.new("ShaderNodeTexEnvironment")
    texture.image = image
    texture.projection = "EQUIRECTANGULAR"
    texture.interpolation = getattr(args, "sky_interpolation", "Linear")
    links.new(coordinates.outputs["Generated"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], texture.inputs["Vector"])
    links.new(texture.outputs["Color"], background.inputs["Color"])
    background.inputs["Strength"].default_value = getattr(args, "sky_intensity", 1.0)
    world.cycles.sampling_method = "MANUAL"  # "Sample as light": importance-sampled, with MIS
    world.cycles.sample_map_resolution = image.size[0]  # a width x width/2 map: the image's own
    return world


def add_sun(scene, args):
    """A Blender SUN of strength E (W/m^2 on a facing surface) shining along the glTF direction."""
    import mathutils
    dx, dy, dz = args.sun
    travel = mathutils.Vector((dx, -dz, dy)).normalized()  # glTF (x, y, z) -> Blender (x, -z, y)
    light = bpy.data.lights.new("sun", type="SUN")
    light.energy = args.sun_irradiance
    light.color = args.sun_color
    light.angle = math.radians(args.sun_angle)
    obj = bpy.data.objects.new("sun", light)
    obj.rotation_mode = "QUATERNION"
    obj.rotation_quaternion = (-travel).to_track_quat("Z", "Y")  # local +Z towards the sun: it shines along -Z
    scene.collection.objects.link(obj)
    return list(obj.rotation_quaternion @ mathutils.Vector((0.0, 0.0, -1.0)))  # Blender axes


def make_one_sided_emitter(material):
    """Front-only emission, Lambert reflection on both sides (see --one-sided-emitters)."""
    if material is None or not material.use_nodes or not emits(material) or not material.use_backface_culling:
        return False
    nodes, links = material.node_tree.nodes, material.node_tree.links
    principled = next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)
    output = next((n for n in nodes if n.type == "OUTPUT_MATERIAL"), None)
    if principled is None or output is None:
        raise SystemExit("cycles_bake.py: --one-sided-emitters: material %r is not a Principled BSDF" % material.name)
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Roughness"].default_value = 0.0
    emission = nodes.new("ShaderNodeEmission")
    for source, target in ((principled.inputs["Base Color"], diffuse.inputs["Color"]),
                           (principled.inputs["Emission"], emission.inputs["Color"])):
        if source.is_linked:
            links.new(source.links[0].from_socket, target)
        else:
            target.default_value = source.default_value
    strength = principled.inputs["Emission Strength"]
    if strength.is_linked:
        links.new(strength.links[0].from_socket, emission.inputs["Strength"])
    else:
        emission.inputs["Strength"].default_value = strength.default_value
    front = nodes.new("ShaderNodeAddShader")
    links.new(diffuse.outputs["BSDF"], front.inputs[0])
    links.new(emission.outputs["Emission"], front.inputs[1])
    geometry = nodes.new("ShaderNodeNewGeometry")
    mix = nodes.new("ShaderNodeMixShader")  # Fac 0 (front): input 1; Fac 1 (back): input 2
    links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    links.new(front.outputs["Shader"], mix.inputs[1])
    links.new(diffuse.outputs["BSDF"], mix.inputs[2])
    links.new(mix.outputs["Shader"], output.inputs["Surface"])
    return True


def emits(material):
    # voxlight does not bake emitter meshes (receivers.h); nor do we.
    if material is None or not material.use_nodes:
        return False
    for node in material.node_tree.nodes:
        if node.type == "BSDF_PRINCIPLED":
            color = node.inputs["Emission"].default_value
            strength = node.inputs["Emission Strength"].default_value if "Emission Strength" in node.inputs else 1.0
            linked = node.inputs["Emission"].is_linked
            if strength > 0.0 and (linked or max(color[0], color[1], color[2]) > 0.0):
                return True
        if node.type == "EMISSION":
            return True
    return False


def make_lambert(material, every=False):
    if material is None or not material.use_nodes or emits(material):
        return False
    nodes, links = material.node_tree.nodes, material.node_tree.links
    principled = next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)
    output = next((n for n in nodes if n.type == "OUTPUT_MATERIAL"), None)
    if principled is None or output is None:
        return False
    if not every and (principled.inputs["Metallic"].is_linked or principled.inputs["Metallic"].default_value > 0.0):
        return False
    if not every and (principled.inputs["Transmission"].is_linked or principled.inputs["Transmission"].default_value > 0.0):
        return False
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Roughness"].default_value = 0.0
    base = principled.inputs["Base Color"]
    if base.is_linked:
        links.new(base.links[0].from_socket, diffuse.inputs["Color"])
    else:
        diffuse.inputs["Color"].default_value = base.default_value
    links.new(diffuse.outputs["BSDF"], output.inputs["Surface"])
    return True


def bake_targets():
    targets = []
    for obj in bpy.context.scene.objects:
        if obj.type != "MESH" or len(obj.data.uv_layers) < 2:
            continue
        if any(emits(slot.material) for slot in obj.material_slots):
            continue
        targets.append(obj)
    return targets


def bake_lightmap(scene, args, timings):
    targets = bake_targets()
    if not targets:
        raise SystemExit("cycles_bake.py: no mesh with TEXCOORD_1 to bake")
    image = bpy.data.images.new("lightmap", args.lightmap_res, args.lightmap_res, alpha=False, float_buffer=True)
    image.colorspace_settings.name = "Linear"
    for material in {slot.material for obj in targets for slot in obj.material_slots if slot.material}:
        material.use_nodes = True
        node = material.node_tree.nodes.new("ShaderNodeTexImage")
        node.image = image
        material.node_tree.nodes.active = node
    bpy.ops.object.select_all(action="DESELECT")
    for obj in targets:
        obj.data.uv_layers.active_index = 1  # TEXCOORD_1: the lightmap set
        obj.select_set(True)
    bpy.context.view_layer.objects.active = targets[0]
    bake = scene.render.bake
    bake.use_pass_color = False
    bake.margin = 0
    bake.target = "IMAGE_TEXTURES"
    for name, passes in (("lightmap", {"DIRECT", "INDIRECT"}), ("lightmap_direct", {"DIRECT"})):
        mask = args.mask and name == "lightmap"
        if mask:  # texels the bake leaves alone keep the sentinel
            image.pixels.foreach_set(numpy.full(len(image.pixels), -1.0, dtype=numpy.float32))
        start, cpu = time.perf_counter(), time.process_time()
        bpy.ops.object.bake(type="DIFFUSE", pass_filter=passes, use_clear=not mask, margin=0)
        timings[name + "_seconds"] = time.perf_counter() - start
        timings[name + "_cpu_seconds"] = time.process_time() - cpu
        if mask:
            pixels = numpy.empty(len(image.pixels), dtype=numpy.float32)
            image.pixels.foreach_get(pixels)
            pixels = pixels.reshape(-1, 4)
            covered = pixels[:, 0] != -1.0
            pixels[~covered, :3] = 0.0
            pixels[:, 3] = 1.0
            image.pixels.foreach_set(pixels.ravel())
            image.save_render(os.path.join(args.out, name + ".exr"), scene=scene)
            timings["lightmap_covered_texels"] = int(covered.sum())
            ones = numpy.repeat(covered.astype(numpy.float32), 4).reshape(-1, 4)
            ones[:, 3] = 1.0
            image.pixels.foreach_set(ones.ravel())
            image.save_render(os.path.join(args.out, "lightmap_mask.exr"), scene=scene)
            continue
        image.save_render(os.path.join(args.out, name + ".exr"), scene=scene)


def render_image(scene, args, timings):
    cameras = [obj for obj in scene.objects if obj.type == "CAMERA"]
    if not cameras:
        raise SystemExit("cycles_bake.py: the scene has no camera")
    scene.camera = cameras[0]
    scene.render.resolution_x = args.width
    scene.render.resolution_y = args.height
    scene.render.resolution_percentage = 100
    start, cpu = time.perf_counter(), time.process_time()
    bpy.ops.render.render(write_still=False)
    timings["image_seconds"] = time.perf_counter() - start
    timings["image_cpu_seconds"] = time.process_time() - cpu
    bpy.data.images["Render Result"].save_render(os.path.join(args.out, "image.exr"), scene=scene)


def main():
    args = parse_args()
    os.makedirs(args.out, exist_ok=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    timings = {"spp": args.spp, "seed": args.seed, "blender": bpy.app.version_string}
    if args.sky is not None:
        timings["sky"] = list(args.sky)
    if args.sky_image is not None:
        timings["sky_image"] = {"path": args.sky_image, "rotation_degrees": args.sky_rotation,
                                "intensity": args.sky_intensity, "interpolation": args.sky_interpolation}
    start = time.perf_counter()
    bpy.ops.import_scene.gltf(filepath=args.scene)
    timings["import_seconds"] = time.perf_counter() - start
    scene = bpy.context.scene
    configure(scene, args)
    timings["lambert_materials"] = sorted(m.name for m in bpy.data.materials if make_lambert(m, args.lambert_all))
    if args.one_sided_emitters:
        timings["one_sided_emitters"] = sorted(m.name for m in bpy.data.materials if make_one_sided_emitter(m))
    if args.sun is not None:
        timings["sun"] = {"direction_gltf": list(args.sun), "irradiance": args.sun_irradiance,
                          "angle_degrees": args.sun_angle, "color": list(args.sun_color),
                          "direction_blender": add_sun(scene, args)}
    if not args.no_lightmap:
        bake_lightmap(scene, args, timings)
    if not args.no_image:
        render_image(scene, args, timings)
    # CPU of what a user would run: the total lightmap and the image (the direct bake only
    # serves the bench's indirect figures).
    timings["cpu_seconds"] = timings.get("lightmap_cpu_seconds", 0.0) + timings.get("image_cpu_seconds", 0.0)
    timings["peak_memory_bytes"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    with open(os.path.join(args.out, "cycles.json.tmp"), "w") as out:
        json.dump(timings, out, indent=2)
    os.replace(os.path.join(args.out, "cycles.json.tmp"), os.path.join(args.out, "cycles.json"))


if __name__ == "__main__":
    main()
