// Where a ray leaving a surface should start so it does not hit that surface again, at any
// scale: Wächter & Binder, "A Fast and Robust Method for Avoiding Self-Intersection" (Ray
// Tracing Gems, ch. 6). The hit point is moved along the geometric normal by a fixed number
// of float ulps (so the offset grows with the coordinates' magnitude, where rounding error
// grows too), and near the origin, where ulps vanish, by a small amount relative to the
// scene's extent (the paper's 1/65536 within 1/32 of the origin, for a scene about a unit
// across; scenes sit centred on their local origin, scene.h). No fixed length: the same code
// works for a 1 mm and a 1 km scene.
//
//   const vec3 n = dot(Ng, outgoing) > 0 ? Ng : -Ng;   // the side the new ray leaves to
//   Ray next{offsetRayOrigin(hitPoint, n, bvh.extent), outgoing};
//
// For a shadow ray towards a light at point L, also offset the far end (offsetRayOrigin(L,
// n_L)) or shorten tMax, so the light's own surface is not counted as an occluder.
#pragma once

#include "core/math.h"

#include <cstring>

namespace vl {

VL_HOSTDEV inline int32_t floatAsInt(float f) {
#if defined(__CUDA_ARCH__)
    return __float_as_int(f);
#else
    int32_t i;
    std::memcpy(&i, &f, sizeof i);
    return i;
#endif
}

VL_HOSTDEV inline float intAsFloat(int32_t i) {
#if defined(__CUDA_ARCH__)
    return __int_as_float(i);
#else
    float f;
    std::memcpy(&f, &i, sizeof f);
    return f;
#endif
}

// p: a point on the surface (as computed from the hit, with its rounding error);
// normal: unit geometric normal pointing to the side the new ray leaves to; extent: the
// scene's size (BvhView::extent), positive.
VL_HOSTDEV inline vec3 offsetRayOrigin(const vec3& p, const vec3& normal, float extent) {
    const float originRegion = extent * (1.0f / 32.0f);  // below this |coordinate|, ulps are too small
    const float floatScale = extent * (1.0f / 65536.0f);  // the offset used there
    constexpr float kIntScale = 256.0f;                    // ulps moved per unit of normal
    vec3 out;
    for (int i = 0; i < 3; ++i) {
        const int32_t ulps = static_cast<int32_t>(kIntScale * normal[i]);
        // Stepping the bit pattern moves away from zero for positive floats and towards
        // zero for negative ones, hence the sign flip.
        const float stepped = intAsFloat(floatAsInt(p[i]) + (p[i] < 0.0f ? -ulps : ulps));
        out[i] = glm::abs(p[i]) < originRegion ? p[i] + floatScale * normal[i] : stepped;
    }
    return out;
}

}  // namespace vl
