#pragma once

#include "core/math.h"

namespace vl {

struct Aabb {
    vec3 lower{kInfinity};
    vec3 upper{-kInfinity};

    VL_HOSTDEV bool empty() const { return lower.x > upper.x || lower.y > upper.y || lower.z > upper.z; }
    VL_HOSTDEV void extend(const vec3& p) { lower = glm::min(lower, p); upper = glm::max(upper, p); }
    VL_HOSTDEV void extend(const Aabb& b) { lower = glm::min(lower, b.lower); upper = glm::max(upper, b.upper); }
    VL_HOSTDEV vec3 extent() const { return upper - lower; }
    VL_HOSTDEV vec3 centre() const { return 0.5f * (lower + upper); }
    VL_HOSTDEV float surfaceArea() const {
        if (empty()) return 0.0f;
        const vec3 d = extent();
        return 2.0f * (d.x * d.y + d.y * d.z + d.z * d.x);
    }
    VL_HOSTDEV int longestAxis() const {
        const vec3 d = extent();
        return d.x >= d.y && d.x >= d.z ? 0 : (d.y >= d.z ? 1 : 2);
    }
};

}  // namespace vl
