// Watertight ray–triangle intersection (Woop, Benthin, Wald 2013, "Watertight Ray/Triangle
// Intersection", JCGT 2(1)); ERRATA eq. 12–13 asks for watertightness, not Möller–Trumbore's
// epsilon. The vertices are translated to the ray origin and sheared so the ray becomes
// +z through (0,0); the 2D edge functions are then exact in sign (double fallback when a
// float product rounds to 0), so a ray through a shared edge never slips between the two
// triangles. An edge function exactly 0 is broken by a consistent tie rule (the sign a
// tiny fixed perturbation of the ray would give), so a ray through a shared edge or vertex
// of a closed mesh hits exactly one triangle, whichever side faces it.
#pragma once

#include "core/math.h"
#include "core/ray.h"

namespace vl {

// Per-ray data for the watertight test: computed once per ray, reused for every triangle.
struct WatertightRay {
    int kx, ky, kz;    // axis permutation: kz is the dominant direction axis
    float sx, sy, sz;  // shear taking the direction to (0, 0, 1)
    float ox, oy, oz;  // origin, permuted
};

// Component i of v. glm's operator[] is a switch, which the triangle test would run with
// run-time axes for every triangle.
VL_HOSTDEV inline float component(const vec3& v, int i) { return (&v.x)[i]; }

VL_HOSTDEV inline WatertightRay makeWatertightRay(const vec3& origin, const vec3& direction) {
    WatertightRay r;
    const vec3 a = glm::abs(direction);
    r.kz = a.x >= a.y ? (a.x >= a.z ? 0 : 2) : (a.y >= a.z ? 1 : 2);
    r.kx = r.kz == 2 ? 0 : r.kz + 1;
    r.ky = r.kx == 2 ? 0 : r.kx + 1;
    // Swapping kx and ky for a negative dominant component keeps the winding, so the sign
    // of the edge functions means the same thing for every ray.
    if (component(direction, r.kz) < 0.0f) {
        const int tmp = r.kx;
        r.kx = r.ky;
        r.ky = tmp;
    }
    r.sx = component(direction, r.kx) / component(direction, r.kz);
    r.sy = component(direction, r.ky) / component(direction, r.kz);
    r.sz = 1.0f / component(direction, r.kz);
    r.ox = component(origin, r.kx);
    r.oy = component(origin, r.ky);
    r.oz = component(origin, r.kz);
    return r;
}

// The sign the edge function from a to b (sheared 2D coordinates) takes at the ray when
// the ray is nudged by (−ε, ε²): decides rays exactly on an edge. The opposite edge (b to
// a) of the neighbouring triangle gets the opposite sign, so exactly one of them owns it.
VL_HOSTDEV inline bool edgeTieIsPositive(float ax, float ay, float bx, float by) {
    const float dy = by - ay;
    return dy > 0.0f || (dy == 0.0f && bx - ax > 0.0f);
}

struct TriangleHit {
    float t = 0.0f;
    float b1 = 0.0f, b2 = 0.0f;  // point = (1-b1-b2)·v0 + b1·v1 + b2·v2
};

// Hit iff t ∈ (tMin, tMax). Both faces are hit; a degenerate triangle is never hit.
VL_HOSTDEV inline bool intersectTriangle(const WatertightRay& ray, const vec3& v0, const vec3& v1,
                                         const vec3& v2, float tMin, float tMax, TriangleHit& hit) {
    // Translate to the origin, then shear: the ray becomes the +z axis through (0, 0).
    const float az = component(v0, ray.kz) - ray.oz;
    const float bz = component(v1, ray.kz) - ray.oz;
    const float cz = component(v2, ray.kz) - ray.oz;
    const float ax = (component(v0, ray.kx) - ray.ox) - ray.sx * az;
    const float ay = (component(v0, ray.ky) - ray.oy) - ray.sy * az;
    const float bx = (component(v1, ray.kx) - ray.ox) - ray.sx * bz;
    const float by = (component(v1, ray.ky) - ray.oy) - ray.sy * bz;
    const float cx = (component(v2, ray.kx) - ray.ox) - ray.sx * cz;
    const float cy = (component(v2, ray.ky) - ray.oy) - ray.sy * cz;

    // u weights v0 (edge v2→v1), v weights v1 (edge v0→v2), w weights v2 (edge v1→v0).
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    // Strictly mixed signs: a miss whatever the exact zeros below would decide (the common
    // case, so it comes first).
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return false;
    if (u == 0.0f || v == 0.0f || w == 0.0f) {
        // float×float is exact in double, so an edge that rounds to 0 gets its exact sign.
        // Each edge's value depends only on that edge's two vertices, so the neighbouring
        // triangle computes exactly the negated value for the shared edge: no gap, no
        // double count. An edge still exactly 0 goes to the tie rule.
        if (u == 0.0f) u = static_cast<float>(static_cast<double>(cx) * by - static_cast<double>(cy) * bx);
        if (v == 0.0f) v = static_cast<float>(static_cast<double>(ax) * cy - static_cast<double>(ay) * cx);
        if (w == 0.0f) w = static_cast<float>(static_cast<double>(bx) * ay - static_cast<double>(by) * ax);
        const bool uPos = u != 0.0f ? u > 0.0f : edgeTieIsPositive(cx, cy, bx, by);
        const bool vPos = v != 0.0f ? v > 0.0f : edgeTieIsPositive(ax, ay, cx, cy);
        const bool wPos = w != 0.0f ? w > 0.0f : edgeTieIsPositive(bx, by, ax, ay);
        if (uPos != vPos || vPos != wPos) return false;
    }

    const float det = u + v + w;
    if (det == 0.0f) return false;
    // Reject by distance before dividing (most candidates in a leaf are behind the closest
    // hit); the exact test on t below decides the rest.
    // t·|det| against tMin·|det| and tMax·|det|, with a margin far above their rounding.
    const float scaledT = ray.sz * (u * az + v * bz + w * cz);
    const float absDet = glm::abs(det);
    const float tTimesAbsDet = det > 0.0f ? scaledT : -scaledT;
    const float lowest = tMin * absDet, highest = tMax * absDet;
    if (tTimesAbsDet < lowest - glm::abs(lowest) * 0x1p-20f || tTimesAbsDet > highest + glm::abs(highest) * 0x1p-20f)
        return false;
    const float invDet = 1.0f / det;
    const float t = scaledT * invDet;
    // Written so a NaN t is rejected.
    if (!(t > tMin && t < tMax)) return false;
    hit.t = t;
    hit.b1 = v * invDet;
    hit.b2 = w * invDet;
    return true;
}

// Convenience for one-off tests; traversal builds the WatertightRay once per ray instead.
VL_HOSTDEV inline bool intersectTriangle(const Ray& ray, const vec3& v0, const vec3& v1, const vec3& v2,
                                         TriangleHit& hit) {
    return intersectTriangle(makeWatertightRay(ray.origin, ray.direction), v0, v1, v2, ray.tMin, ray.tMax,
                             hit);
}

}  // namespace vl
