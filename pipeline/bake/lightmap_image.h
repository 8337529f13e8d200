// The lightmap-lit image: a camera as an engine shows the bake, in linear light.
//
// Takes a camera's receivers (receivers.h buildCameraReceivers: the primary rays, pixel
// sub-samples and emission the bake's own image is shaded from), the scene's TEXCOORD_1 and
// the lightmaps as they ship. Gives, per pixel,
//     emission + Σ weight · albedo · light
// over the pixel's samples, where `light` is:
//   - for a sample on a mesh baked into a lightmap: that lightmap read bilinearly at the
//     sample's TEXCOORD_1, texel centres at (i + ½) / size, clamped at the image's edges
//     (tools/viewer/viewer.js lightmapAt);
//   - for any other surface (an emitter, a mesh without TEXCOORD_1, a mesh no atlas took):
//     kUnlitLight, what the viewer shows there (viewer.js UNLIT_LEVEL).
// So the image differs from the bake's own only in where the light comes from: texels, not
// the receivers' gather. A sample stands for the rays of its pixel that hit its triangle
// (their hits merged, receivers.h), and reads the lightmap once at their centroid, as it is
// shaded once in the bake's image.
//
// "As they ship": shippedLightmapTexels gives the texels scene.glb carries, the dilated total
// through 8-bit RGBM and back (export/lightmap_encoding.h), which is what the viewer decodes,
// texel by texel, before it filters.
#pragma once

#include "bake/receivers.h"
#include "core/image.h"
#include "scene/scene.h"
#include "trace/bvh.h"

#include <cstdint>
#include <vector>

namespace vl {

// E/π that a surface outside every lightmap shows: tools/viewer/viewer.js UNLIT_LEVEL.
constexpr float kUnlitLight = 0.1f;

struct ShippedLightmap {
    std::vector<uint32_t> meshes;  // indices into Scene::meshes baked into it
    Image texels;                  // RGB E/π, rows from the top (glTF's v down)
};

// A lightmap's total (padding dilated) as scene.glb carries it and the viewer decodes it.
Image shippedLightmapTexels(const Image& total);

// TEXCOORD_1 at `point` on triangle `localTriangle` of `mesh` (`corners`: its world-space
// corners); NaN where the mesh has no uv1 for it.
vec2 lightmapUvAt(const Mesh& mesh, uint32_t localTriangle, const vec3* corners, const vec3& point);

// The lightmap at TEXCOORD_1 `uv`, bilinear between texel centres, clamped to the edge.
vec3 sampleLightmap(const Image& texels, vec2 uv);

// `triangles` and the samples' triangle ids follow gatherTriangles(scene).
Image renderLightmapImage(const CameraReceivers& camera, const Scene& scene, const SceneTriangles& triangles,
                          const std::vector<ShippedLightmap>& lightmaps);

}  // namespace vl
