#pragma once

#include "core/math.h"

namespace vl {

struct Ray {
    vec3 origin{0.0f};
    vec3 direction{0.0f, 0.0f, 1.0f};  // unit length unless a caller says otherwise
    float tMin = 0.0f;
    float tMax = kInfinity;

    VL_HOSTDEV vec3 at(float t) const { return origin + t * direction; }
};

}  // namespace vl
