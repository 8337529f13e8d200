// Warps from uniform [0,1)^n to the distributions the integrators need.
#pragma once

#include "core/math.h"
#include "core/rng.h"

namespace vl {

// Shirley–Chiu concentric mapping of the unit square to the unit disk.
VL_HOSTDEV inline vec2 sampleConcentricDisk(vec2 u) {
    const vec2 o = 2.0f * u - vec2(1.0f);
    if (o.x == 0.0f && o.y == 0.0f) return vec2(0.0f);
    float r, theta;
    if (glm::abs(o.x) > glm::abs(o.y)) {
        r = o.x;
        theta = 0.25f * kPi * (o.y / o.x);
    } else {
        r = o.y;
        theta = 0.5f * kPi - 0.25f * kPi * (o.x / o.y);
    }
    return r * vec2(glm::cos(theta), glm::sin(theta));
}

// Cosine-weighted direction about +Z; pdf = cos θ / π.
VL_HOSTDEV inline vec3 sampleCosineHemisphere(vec2 u) {
    const vec2 d = sampleConcentricDisk(u);
    const float z = glm::sqrt(glm::max(0.0f, 1.0f - d.x * d.x - d.y * d.y));
    return vec3(d.x, d.y, z);
}

// The direction in the cone of half-angle acos(cosMax) about +Z that a point of the unit disk
// stands for, area to solid angle: a uniform point of the disk (sampleConcentricDisk) gives a
// uniform direction, and compact strata of the square stay compact in the cone.
VL_HOSTDEV inline vec3 coneDirection(vec2 disk, float cosMax) {
    const float r2 = glm::min(1.0f, disk.x * disk.x + disk.y * disk.y);
    const float z = 1.0f - r2 * (1.0f - cosMax);
    const float r = glm::sqrt(r2);
    const float s = glm::sqrt(glm::max(0.0f, 1.0f - z * z));
    return r > 0.0f ? vec3(disk.x / r * s, disk.y / r * s, z) : vec3(0.0f, 0.0f, 1.0f);
}

// The same about a unit `axis`: a sun's direction for a point of its disk.
VL_HOSTDEV inline vec3 coneDirectionAbout(const vec3& axis, float cosMax, vec2 disk) {
    vec3 t, b;
    orthonormalBasis(axis, t, b);
    const vec3 local = coneDirection(disk, cosMax);
    return glm::normalize(local.x * t + local.y * b + local.z * axis);
}

VL_HOSTDEV inline vec3 sampleUniformSphere(vec2 u) {
    const float z = 1.0f - 2.0f * u.x;
    const float r = glm::sqrt(glm::max(0.0f, 1.0f - z * z));
    const float phi = 2.0f * kPi * u.y;
    return vec3(r * glm::cos(phi), r * glm::sin(phi), z);
}

// Uniform barycentrics (b1, b2) on a triangle; b0 = 1 - b1 - b2.
VL_HOSTDEV inline vec2 sampleUniformTriangle(vec2 u) {
    const float su = glm::sqrt(u.x);
    return vec2(1.0f - su, u.y * su);
}

// The point of stratum (i, j) of an n × n grid over [0, 1)², jittered by a generator of its
// own (seed, sample stream·n² + i·n + j, salt): the same point whatever thread asks.
VL_HOSTDEV inline vec2 jitteredStratum(uint64_t seed, uint64_t stream, int n, int i, int j, uint64_t salt) {
    Pcg32 rng = Pcg32::forItem(seed, stream * uint64_t(n * n) + uint64_t(i * n + j), salt);
    vec2 u;
    rng.next2D(u.x, u.y);
    return (vec2(float(i), float(j)) + u) / static_cast<float>(n);
}

// Tent filter of ERRATA eq. (11): maps ξ ∈ [0,1) to an offset in [-1, 1).
VL_HOSTDEV inline float sampleTent(float xi) {
    return 2.0f * xi < 1.0f ? glm::sqrt(2.0f * xi) - 1.0f : 1.0f - glm::sqrt(2.0f - 2.0f * xi);
}

VL_HOSTDEV inline float powerHeuristic(float pdfA, float pdfB) {
    const float a = pdfA * pdfA;
    const float b = pdfB * pdfB;
    return a + b > 0.0f ? a / (a + b) : 0.0f;
}

}  // namespace vl
