#!/usr/bin/env python3
"""Copy a voxlight scene.glb without its baked lightmap: drops every material's MOZ_lightmap,
the textures and images only MOZ_lightmap used, and their bytes from the binary chunk
(bufferViews renumbered, the buffer repacked 4-byte aligned). Everything else is kept as is.

    python3 strip_lightmap.py IN.glb OUT.glb
"""
import json
import struct
import sys


def main(src, dst):
    data = open(src, "rb").read()
    magic, version, _ = struct.unpack_from("<III", data, 0)
    assert magic == 0x46546C67 and version == 2, "not a glTF 2.0 binary"
    jlen, jtype = struct.unpack_from("<II", data, 12)
    assert jtype == 0x4E4F534A
    gltf = json.loads(data[20:20 + jlen])
    off = 20 + jlen
    blen, btype = struct.unpack_from("<II", data, off)
    assert btype == 0x004E4942
    binary = data[off + 8:off + 8 + blen]

    lightmap_textures = set()
    for material in gltf.get("materials", []):
        ext = material.get("extensions", {})
        if "MOZ_lightmap" in ext:
            lightmap_textures.add(ext.pop("MOZ_lightmap")["index"])
            if not ext:
                del material["extensions"]
    used_textures = set()

    def walk(node):
        if isinstance(node, dict):
            for key, value in node.items():
                if key.endswith("Texture") and isinstance(value, dict) and "index" in value:
                    used_textures.add(value["index"])
                walk(value)
        elif isinstance(node, list):
            for value in node:
                walk(value)
    walk(gltf.get("materials", []))
    drop_textures = lightmap_textures - used_textures
    textures = gltf.get("textures", [])
    keep_t = [i for i in range(len(textures)) if i not in drop_textures]
    tex_map = {old: new for new, old in enumerate(keep_t)}
    used_images = {textures[i]["source"] for i in keep_t}
    images = gltf.get("images", [])
    keep_i = [i for i in range(len(images)) if i in used_images]
    img_map = {old: new for new, old in enumerate(keep_i)}
    gltf["textures"] = [dict(textures[i], source=img_map[textures[i]["source"]]) for i in keep_t]
    gltf["images"] = [images[i] for i in keep_i]

    def remap(node):
        if isinstance(node, dict):
            for key, value in node.items():
                if key.endswith("Texture") and isinstance(value, dict) and "index" in value:
                    value["index"] = tex_map[value["index"]]
                remap(value)
        elif isinstance(node, list):
            for value in node:
                remap(value)
    remap(gltf.get("materials", []))
    for key in ("textures", "images", "samplers"):
        if key in gltf and not gltf[key]:
            del gltf[key]
    if "samplers" in gltf:  # drop samplers no texture uses any more
        used_samplers = sorted({t["sampler"] for t in gltf.get("textures", []) if "sampler" in t})
        sampler_map = {old: new for new, old in enumerate(used_samplers)}
        gltf["samplers"] = [gltf["samplers"][i] for i in used_samplers]
        for t in gltf.get("textures", []):
            if "sampler" in t:
                t["sampler"] = sampler_map[t["sampler"]]
        if not gltf["samplers"]:
            del gltf["samplers"]
    gltf["extensionsUsed"] = [e for e in gltf.get("extensionsUsed", []) if e != "MOZ_lightmap"]
    if not gltf["extensionsUsed"]:
        del gltf["extensionsUsed"]

    # bufferViews still referenced: accessors' and images'
    used_views = {a["bufferView"] for a in gltf.get("accessors", []) if "bufferView" in a}
    used_views |= {i["bufferView"] for i in gltf.get("images", []) if "bufferView" in i}
    views = gltf["bufferViews"]
    out = bytearray()
    view_map, new_views = {}, []
    for i, view in enumerate(views):
        if i not in used_views:
            continue
        assert view.get("buffer", 0) == 0
        start = view.get("byteOffset", 0)
        chunk = binary[start:start + view["byteLength"]]
        while len(out) % 4:
            out.append(0)
        new_view = dict(view, byteOffset=len(out))
        out += chunk
        view_map[i] = len(new_views)
        new_views.append(new_view)
    gltf["bufferViews"] = new_views
    for a in gltf.get("accessors", []):
        if "bufferView" in a:
            a["bufferView"] = view_map[a["bufferView"]]
    for im in gltf.get("images", []):
        if "bufferView" in im:
            im["bufferView"] = view_map[im["bufferView"]]
    while len(out) % 4:
        out.append(0)
    gltf["buffers"][0]["byteLength"] = len(out)

    text = json.dumps(gltf, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(out)
    with open(dst, "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, total))
        f.write(struct.pack("<II", len(text), 0x4E4F534A) + text)
        f.write(struct.pack("<II", len(out), 0x004E4942) + out)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
