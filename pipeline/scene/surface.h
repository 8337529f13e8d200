// Material inputs at a point of a mesh: what the voxelizer, the path tracer and the bake
// all sample, written once.
#pragma once

#include "scene/scene.h"

namespace vl {

// Bilinear (or nearest) lookup with the texture's wrap modes; RGBA, linear.
vec4 sampleTexture(const Texture& texture, vec2 uv);

struct SurfacePoint {
    vec3 position;
    vec3 normal;   // interpolated shading normal, unit
    vec2 uv0;
    vec2 uv1;
};

// Barycentric interpolation over triangle `triangle` of `mesh`, weights (1-b1-b2, b1, b2).
SurfacePoint interpolateSurface(const Mesh& mesh, size_t triangle, vec2 barycentric);

// baseColorFactor × baseColorTexture × COLOR_0 (RGB) and the alpha product.
vec4 baseColorAt(const Scene& scene, const Mesh& mesh, size_t triangle, vec2 barycentric);
// emissiveFactor × emissiveTexture × emissiveStrength, radiance W/(m²·sr).
vec3 emissionAt(const Scene& scene, const Mesh& mesh, size_t triangle, vec2 barycentric);

}  // namespace vl
