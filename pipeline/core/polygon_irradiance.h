// Lambert's closed form for the irradiance a uniformly emitting polygon gives a point: the
// exact unshadowed direct light of an emissive triangle, for the bake's receivers
// (lighting/direct_light.h) and the voxel lighting pass (lighting/lighting_kernels.h).
#pragma once

#include "core/math.h"

namespace vl {

// Clips polygon `in` (count ≤ 3 vertices, relative to the receiver) to the half-space
// dot(x, n) ≥ 0; returns the clipped vertex count (≤ 4).
VL_HOSTDEV inline int clipToHemisphere(const vec3* in, int count, const vec3& n, vec3* out) {
    int outCount = 0;
    for (int i = 0; i < count; ++i) {
        const vec3& a = in[i];
        const vec3& b = in[(i + 1) % count];
        const float da = glm::dot(a, n);
        const float db = glm::dot(b, n);
        if (da >= 0.0f) out[outCount++] = a;
        if ((da >= 0.0f) != (db >= 0.0f)) out[outCount++] = a + (b - a) * (da / (da - db));
    }
    return outCount;
}

// Lambert's formula: the irradiance at the origin, normal n, from a polygon of unit radiance
// (vertices relative to the receiver, above its tangent plane): ½ |Σ_i Θ_i (Γ̂_i · n)|.
VL_HOSTDEV inline float polygonIrradiance(const vec3* vertices, int count, const vec3& n) {
    float sum = 0.0f;
    for (int i = 0; i < count; ++i) {
        const vec3 a = glm::normalize(vertices[i]);
        const vec3 b = glm::normalize(vertices[(i + 1) % count]);
        const vec3 c = glm::cross(a, b);
        const float sinTheta = glm::length(c);
        const float theta = glm::atan(sinTheta, glm::dot(a, b));
        if (sinTheta > 0.0f) sum += theta * glm::dot(c / sinTheta, n);
    }
    return 0.5f * glm::abs(sum);
}

// ∫ max(n·ω, 0) dω over the triangle (vertices relative to the receiver) as seen from the
// receiver: the irradiance per unit radiance on a plane of unit normal n, the part of the
// triangle below the plane clipped away.
VL_HOSTDEV inline float clippedTriangleIrradiance(const vec3 (&relative)[3], const vec3& n) {
    vec3 clipped[4];
    const int count = clipToHemisphere(relative, 3, n, clipped);
    return count >= 3 ? polygonIrradiance(clipped, count, n) : 0.0f;
}

}  // namespace vl
