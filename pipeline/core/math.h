// Vector math for every stage: glm in float, usable in host and device code.
#pragma once

#include "core/hostdev.h"

#include <glm/glm.hpp>

#include <cstdint>

namespace vl {

using glm::ivec3;
using glm::vec2;
using glm::vec3;
using glm::vec4;

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.31830988618379067154f;
constexpr float kInfinity = 3.402823466e+38f;

VL_HOSTDEV inline float maxComponent(const vec3& v) { return glm::max(v.x, glm::max(v.y, v.z)); }
VL_HOSTDEV inline float luminance(const vec3& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }
VL_HOSTDEV inline bool isFinite(float x) { return x - x == 0.0f; }
VL_HOSTDEV inline bool isFinite(const vec3& v) { return isFinite(v.x) && isFinite(v.y) && isFinite(v.z); }

// Orthonormal basis around a unit vector n (Duff et al. 2017, branchless and stable).
VL_HOSTDEV inline void orthonormalBasis(const vec3& n, vec3& t, vec3& b) {
    const float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    const float a = -1.0f / (sign + n.z);
    const float c = n.x * n.y * a;
    t = vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = vec3(c, sign + n.y * n.y * a, -n.y);
}

}  // namespace vl
