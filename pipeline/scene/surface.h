// Material inputs at a point of a mesh: what the voxelizer, the path tracer and the bake
// all sample, written once.
#pragma once

#include "scene/scene.h"

namespace vl {

// Bilinear (or nearest) lookup with the texture's wrap modes; RGBA, linear. glTF's uv
// (0, 0) is the top-left corner of the image; texel centres sit at half-integers. An empty
// image reads as white; a non-finite uv reads as uv (0, 0).
vec4 sampleTexture(const Texture& texture, vec2 uv);

// KHR_texture_transform: uv' = T · R · S · uv (offset, then rotation, then scale, applied
// right to left as the extension specifies).
vec2 transformUv(const TextureTransform& transform, vec2 uv);

struct SurfacePoint {
    vec3 position;
    vec3 normal;   // interpolated shading normal, unit
    vec2 uv0;
    vec2 uv1;
};

// Barycentric interpolation over triangle `triangle` of `mesh`, weights (1-b1-b2, b1, b2).
SurfacePoint interpolateSurface(const Mesh& mesh, size_t triangle, vec2 barycentric);

// The texture `ref` points at, sampled at the point (its TEXCOORD set, its transform);
// white when the reference is unset or the mesh lacks that TEXCOORD set (uv (0, 0) then).
vec4 sampleTextureRef(const Scene& scene, const TextureRef& ref, const Mesh& mesh, size_t triangle,
                      vec2 barycentric);

// baseColorFactor × baseColorTexture × COLOR_0 (RGB) and the alpha product.
vec4 baseColorAt(const Scene& scene, const Mesh& mesh, size_t triangle, vec2 barycentric);
// emissiveFactor × emissiveTexture × emissiveStrength, radiance W/(m²·sr).
vec3 emissionAt(const Scene& scene, const Mesh& mesh, size_t triangle, vec2 barycentric);

}  // namespace vl
