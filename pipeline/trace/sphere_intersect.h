// Ray–sphere intersection for analytic test scenes, in the numerically stable form of
// ERRATA eq. 1 (Haines et al., "Precision Improvements for Ray/Sphere Intersection", Ray
// Tracing Gems ch. 7). With f = O − C the equation is a t² + b t + c = 0, a = d·d,
// b = 2 f·d, c = |f|² − r². The discriminant is taken as 4a(r² − |l|²) with
// l = f − (f·d̂)d̂ (from the centre to the line's closest point), which does not cancel
// when b² ≈ 4ac (a small sphere far away), and the roots as q = −½(b + sign(b)√Δ),
// t₀ = c/q, t₁ = q/a, so the root near zero (an origin close to a large sphere) is not the
// difference of two nearly equal numbers.
//
// Evaluated in double: for an origin on a sphere of radius 1e6, |f|² and r² agree in all
// 24 bits a float has, so c, on which the near root depends entirely, would keep no correct
// digit. Only analytic test scenes use spheres, so the cost does not matter.
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
    const double fx = double(origin.x) - centre.x, fy = double(origin.y) - centre.y, fz = double(origin.z) - centre.z;
    const double dx = direction.x, dy = direction.y, dz = direction.z;
    const double r = radius;
    const double a = dx * dx + dy * dy + dz * dz;
    if (!(a > 0.0)) return false;
    const double fd = fx * dx + fy * dy + fz * dz;
    const double b = 2.0 * fd;
    const double c = (fx * fx + fy * fy + fz * fz) - r * r;
    const double s = fd / a;  // f·d̂ d̂ = (f·d / d·d) d
    const double lx = fx - s * dx, ly = fy - s * dy, lz = fz - s * dz;
    const double lengthL = glm::sqrt(lx * lx + ly * ly + lz * lz);
    const double discriminant = 4.0 * a * (r + lengthL) * (r - lengthL);
    if (discriminant < 0.0) return false;
    const double root = glm::sqrt(discriminant);
    const double q = -0.5 * (b + (b >= 0.0 ? root : -root));
    double t0, t1;
    if (q == 0.0) {
        // b = 0 and Δ = 0: the origin is the point where the line touches the sphere.
        t0 = t1 = 0.0;
    } else {
        t0 = c / q;
        t1 = q / a;
    }
    roots.t0 = static_cast<float>(glm::min(t0, t1));
    roots.t1 = static_cast<float>(glm::max(t0, t1));
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
