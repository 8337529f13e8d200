// BVH traversal: closest hit and any hit (shadow rays), inline VL_HOSTDEV over a BvhView
// so the TBB and CUDA paths run the same code. Stack-based, near child first.
//
//   Hit hit;
//   if (intersectClosest(bvh.view(), ray, hit)) { ... hit.t, hit.triangle, hit.b1, hit.b2 }
//   bool blocked = intersectAny(bvh.view(), shadowRay);   // segment (tMin, tMax)
//
// Both honour ray.tMin < t < ray.tMax; ray.direction need not be unit length (t is then in
// units of the direction's length).
#pragma once

#include "trace/bvh.h"
#include "trace/triangle_intersect.h"

namespace vl {

// Per-ray data for the slab test. A zero (or denormal) direction component gives an
// infinite inverse, and for an origin exactly on a slab plane (bound − origin)·inf = 0·inf
// = NaN; `parallelToAxis` says the ray has such a component, so only those rays pay for
// the NaN handling in intersectBox.
struct RayBoxData {
    vec3 origin;
    vec3 invDirection;
    bool parallelToAxis;
};

VL_HOSTDEV inline RayBoxData makeRayBoxData(const Ray& ray) {
    const vec3 inv(1.0f / ray.direction.x, 1.0f / ray.direction.y, 1.0f / ray.direction.z);
    return {ray.origin, inv, !isFinite(inv)};
}

// Slab test (Williams et al. 2005) with Ize's conservative rounding ("Robust BVH Ray
// Traversal", JCGT 2013): the far distance is scaled by 1 + 2γ₃ so rounding in
// (bound − origin)·invDirection never culls a box the ray touches. With ParallelToAxis, a
// NaN slab distance (origin on a plane of a slab the ray runs parallel to) means the ray
// lies in that plane, which the slab does not restrict: a ray along the face of a box
// still enters it (Ize's 0·inf case). Returns the entry distance in tNear.
template <bool ParallelToAxis>
VL_HOSTDEV inline bool intersectBox(const Aabb& box, const RayBoxData& ray, float tMin, float tMax, float& tNear) {
    constexpr float kFarScale = 1.0f + 2.0f * (3.0f * 0x1p-24f) / (1.0f - 3.0f * 0x1p-24f);
    float enter = tMin, leave = tMax;
    for (int axis = 0; axis < 3; ++axis) {
        const float t0 = (box.lower[axis] - ray.origin[axis]) * ray.invDirection[axis];
        const float t1 = (box.upper[axis] - ray.origin[axis]) * ray.invDirection[axis];
        float nearAxis = glm::min(t0, t1), farAxis = glm::max(t0, t1);
        if (ParallelToAxis && (t0 != t0 || t1 != t1)) {
            nearAxis = -kInfinity;
            farAxis = kInfinity;
        }
        enter = glm::max(enter, nearAxis);
        leave = glm::min(leave, farAxis);
    }
    tNear = enter;
    return enter <= leave * kFarScale;
}

// Deep enough for any tree Bvh::build makes (it caps the depth at kBvhMaxDepth).
constexpr int kBvhStackSize = 64;

namespace detail {

template <bool AnyHit, bool ParallelToAxis>
VL_HOSTDEV inline bool traverse(const BvhView& bvh, const Ray& ray, const RayBoxData& boxRay, Hit& hit) {
    const WatertightRay triRay = makeWatertightRay(ray.origin, ray.direction);
    float tMax = ray.tMax;
    bool found = false;

    float tRoot;
    if (!intersectBox<ParallelToAxis>(bvh.nodes[0].bounds, boxRay, ray.tMin, tMax, tRoot)) return false;

    uint32_t stack[kBvhStackSize];
    float stackNear[kBvhStackSize];
    int top = 0;
    uint32_t current = 0;
    for (;;) {
        const BvhNode& node = bvh.nodes[current];
        if (node.count > 0) {
            const uint32_t end = node.firstOrChild + node.count;
            for (uint32_t slot = node.firstOrChild; slot < end; ++slot) {
                TriangleHit th;
                const vec3* v = bvh.vertices + 3 * static_cast<size_t>(slot);
                if (intersectTriangle(triRay, v[0], v[1], v[2], ray.tMin, tMax, th)) {
                    found = true;
                    if (AnyHit) return true;
                    tMax = th.t;
                    hit.t = th.t;
                    hit.b1 = th.b1;
                    hit.b2 = th.b2;
                    hit.triangle = bvh.triangleIds[slot];
                }
            }
        } else {
            const uint32_t left = current + 1;
            const uint32_t right = node.firstOrChild;
            float nearLeft, nearRight;
            const bool hitLeft = intersectBox<ParallelToAxis>(bvh.nodes[left].bounds, boxRay, ray.tMin, tMax, nearLeft);
            const bool hitRight = intersectBox<ParallelToAxis>(bvh.nodes[right].bounds, boxRay, ray.tMin, tMax, nearRight);
            if (hitLeft && hitRight) {
                const bool leftFirst = nearLeft <= nearRight;
                stack[top] = leftFirst ? right : left;
                stackNear[top] = leftFirst ? nearRight : nearLeft;
                ++top;
                current = leftFirst ? left : right;
                continue;
            }
            if (hitLeft) {
                current = left;
                continue;
            }
            if (hitRight) {
                current = right;
                continue;
            }
        }
        // Pop, skipping subtrees that start beyond the closest hit found since the push.
        for (;;) {
            if (top == 0) return found;
            --top;
            if (stackNear[top] <= tMax * (1.0f + 4.0f * 0x1p-24f)) break;
        }
        current = stack[top];
    }
}

template <bool AnyHit>
VL_HOSTDEV inline bool traverse(const BvhView& bvh, const Ray& ray, Hit& hit) {
    if (bvh.nodeCount == 0) return false;
    const RayBoxData boxRay = makeRayBoxData(ray);
    return boxRay.parallelToAxis ? traverse<AnyHit, true>(bvh, ray, boxRay, hit)
                                 : traverse<AnyHit, false>(bvh, ray, boxRay, hit);
}

}  // namespace detail

// Closest hit in (ray.tMin, ray.tMax); fills hit (t, triangle, b1, b2) and returns true.
// hit is left untouched on a miss.
VL_HOSTDEV inline bool intersectClosest(const BvhView& bvh, const Ray& ray, Hit& hit) {
    return detail::traverse<false>(bvh, ray, hit);
}

// Whether anything lies in (ray.tMin, ray.tMax): stops at the first hit found.
VL_HOSTDEV inline bool intersectAny(const BvhView& bvh, const Ray& ray) {
    Hit unused;
    return detail::traverse<true>(bvh, ray, unused);
}

}  // namespace vl
