// The lightmap-lit image: a camera as an engine shows the bake, in linear light.
//
// Takes a camera (its model and the receivers the bake's own image is shaded from, for the
// emission and sky seen directly), the scene's TEXCOORD_1 and the lightmaps as they ship
// (dilated, through 8-bit RGBM and back, as the viewer decodes them); gives per pixel the
// mean of n × n primary rays, each showing albedo × the lightmap read at its hit
// (renderLightmapImage says how). It differs from the bake's own image only in where the
// light comes from (texels, not the receivers' gather) and in its rays.
#pragma once

#include "receivers/receivers.h"
#include "core/image.h"
#include "scene/scene.h"
#include "trace/bvh.h"
#include "trace/camera.h"

#include <cstdint>
#include <utility>
#include <vector>

namespace vl {

// E/π that a surface outside every lightmap shows: tools/viewer/viewer.js UNLIT_LEVEL.
constexpr float kUnlitLight = 0.1f;

struct ShippedLightmap {
    std::vector<uint32_t> meshes;  // indices into Scene::meshes baked into it
    Image texels;                  // RGB E/π, rows from the top (glTF's v down)
    Image shadowmask;              // RGBA 0..1 as it ships (8-bit, decoded); empty: none

    ShippedLightmap() = default;
    ShippedLightmap(std::vector<uint32_t> meshes_, Image texels_, Image shadowmask_ = Image())
        : meshes(std::move(meshes_)), texels(std::move(texels_)), shadowmask(std::move(shadowmask_)) {}
};

// A lightmap's total (padding dilated) as scene.glb carries it and the viewer decodes it,
// texel by texel, before it filters: through 8-bit RGBM and back (export/lightmap_encoding.h).
Image shippedLightmapTexels(const Image& total);
// A shadowmask (RGBA 0..1) as scene.glb carries it: through 8-bit and back
// (export/lightmap_encoding.h shadowmaskBytes). Empty stays empty.
Image shippedShadowmask(const Image& mask);

// TEXCOORD_1 at `point` on triangle `localTriangle` of `mesh` (`corners`: its world-space
// corners); NaN where the mesh has no uv1 for it.
vec2 lightmapUvAt(const Mesh& mesh, uint32_t localTriangle, const vec3* corners, const vec3& point);

// The lightmap at TEXCOORD_1 `uv`, bilinear between texel centres, clamped to the edge.
vec3 sampleLightmap(const Image& texels, vec2 uv);
// Channel `channel` of an image read as sampleLightmap reads (a shadowmask's light).
float sampleLightmapChannel(const Image& texels, vec2 uv, int channel);

class TraceScene;

// The image, per pixel
//     emission + (1/n²) Σ albedo · light
// over an n × n grid of primary rays (the receivers' film grid, each ray at its own hit),
// where `light` is:
//   - for a hit on a mesh baked into a lightmap: that lightmap read bilinearly at the hit's
//     TEXCOORD_1, texel centres at (i + ½) / size, clamped at the image's edges
//     (tools/viewer/viewer.js lightmapAt);
//   - for any other surface (an emitter, a mesh without TEXCOORD_1, a mesh no atlas took):
//     kUnlitLight, what the viewer shows there (viewer.js UNLIT_LEVEL);
//   - plus, for the lights an engine draws (LightBake::Indirect, which the lightmaps leave
//     out), their exact direct light E/π at the hit: a shadow ray a read (a sun's disk by
//     lighting/direct_light.h sunIrradiance), as an engine's shadow maps draw them;
//   - plus, for a LightBake::Shadowmask light, its unshadowed direct light E·cos θ/π at the hit
//     (a sun from its disk's centre, as an engine's directional light) times its channel of
//     the hit's lightmap's shadowmask, read as the lightmap is (0 where the mesh has none).
// So it differs from the bake's own image in where the light comes from (texels, not the
// receivers' gather) and in its rays: the bake's image shades its 2 × 2 a pixel merged per
// triangle. The n² reads a pixel are its 1-pixel box, as the Cycles references
// filter theirs and as a display of finer pixels shows the lightmap: where light changes
// inside a pixel (a sun edge, a mullion's shadow) the pixel shows its mean, not one side of
// it. n = 1 is one read at the pixel's centre, what the viewer's page shows at that size.
//
// `camera`: the receivers of `model` (their emission image: what is seen directly);
// `raysPerAxis` n in 1..16 (SettingsError otherwise); `triangles` follow gatherTriangles(scene),
// as `trace` and `bvh` do (their meshIndex and localIndex are read; the vertices are trace's).
Image renderLightmapImage(const CameraReceivers& camera, const TraceScene& trace, const Bvh& bvh,
                          const CameraModel& model, int raysPerAxis, const Scene& scene,
                          const SceneTriangles& triangles, const std::vector<ShippedLightmap>& lightmaps);

}  // namespace vl
