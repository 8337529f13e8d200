// Ray–sphere intersection for analytic test scenes, in the numerically stable form of
// ERRATA eq. 1 (Haines et al., "Precision Improvements for Ray/Sphere Intersection", Ray
// Tracing Gems ch. 7): with f = O − C the equation is a t² + b t + c = 0, a = d·d,
// b = 2 f·d, c = f·f − r². The discriminant is taken as 4a(r² − |f − (f·d̂)d̂|²), which
// does not cancel when b² ≈ 4ac, and the roots as q = −½(b + sign(b)√Δ), t₀ = c/q, t₁ = q/a,
// so the root near zero (origin close to a large sphere) is not the difference of two
// nearly equal numbers.
#pragma once

#include "core/math.h"
#include "core/ray.h"

namespace vl {

struct SphereRoots {
    float t0, t1;  // t0 ≤ t1
};

// Both roots of the ray's line against the sphere; false when the line misses it.
VL_HOSTDEV inline bool sphereRoots(const vec3& centre, float radius, const vec3& origin, const vec3& direction,
                                   SphereRoots& roots) {
    const vec3 f = origin - centre;
    const float a = glm::dot(direction, direction);
    if (!(a > 0.0f)) return false;
    const float b = 2.0f * glm::dot(f, direction);
    const float c = glm::dot(f, f) - radius * radius;
    const vec3 unitDirection = direction / glm::sqrt(a);
    const vec3 l = f - glm::dot(f, unitDirection) * unitDirection;  // from centre to the closest point
    const float discriminant = 4.0f * a * (radius + glm::length(l)) * (radius - glm::length(l));
    if (discriminant < 0.0f) return false;
    const float root = glm::sqrt(discriminant);
    const float q = -0.5f * (b + (b >= 0.0f ? root : -root));
    if (q == 0.0f) {
        // b = 0 and Δ = 0: the origin is the point where the line touches the sphere.
        roots.t0 = roots.t1 = 0.0f;
        return true;
    }
    float t0 = c / q, t1 = q / a;
    if (t0 > t1) {
        const float tmp = t0;
        t0 = t1;
        t1 = tmp;
    }
    roots.t0 = t0;
    roots.t1 = t1;
    return true;
}

// Nearest root in (ray.tMin, ray.tMax).
VL_HOSTDEV inline bool intersectSphere(const vec3& centre, float radius, const Ray& ray, float& t) {
    SphereRoots roots;
    if (!sphereRoots(centre, radius, ray.origin, ray.direction, roots)) return false;
    if (roots.t0 > ray.tMin && roots.t0 < ray.tMax) {
        t = roots.t0;
        return true;
    }
    if (roots.t1 > ray.tMin && roots.t1 < ray.tMax) {
        t = roots.t1;
        return true;
    }
    return false;
}

}  // namespace vl
