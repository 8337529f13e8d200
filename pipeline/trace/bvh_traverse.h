// BVH traversal: closest hit and any hit (shadow rays), inline VL_HOSTDEV over a BvhView
// so the TBB and CUDA paths run the same code. Stack-based, near child first.
//
//   Hit hit;
//   if (intersectClosest(bvh.view(), ray, hit)) { ... hit.t, hit.triangle, hit.b1, hit.b2 }
//   bool blocked = intersectAny(bvh.view(), shadowRay);   // segment (tMin, tMax)
//
// Both honour ray.tMin < t < ray.tMax; ray.direction need not be unit length (t is then in
// units of the direction's length). With BvhView::wideNodes set (Bvh::view() sets it) the
// 4-wide nodes are walked, one SIMD slab test per node; without, the binary nodes: the hits
// are the same, the wide walk is faster on the CPU. A CUDA launcher may copy either.
#pragma once

#include "trace/bvh.h"
#include "trace/triangle_intersect.h"

#if defined(__SSE2__) && !defined(__CUDA_ARCH__)
#include <immintrin.h>
#endif

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

// The slab test of intersectBox for the four lanes of a wide node at once: SSE on x86
// hosts, a four-iteration loop elsewhere (CUDA: one thread per ray). Returns the lanes hit
// as bits 0–3 and each lane's entry distance in enter.
template <bool ParallelToAxis>
VL_HOSTDEV inline int intersectBoxes4(const BvhWideNode& node, const RayBoxData& ray, float tMin, float tMax,
                                      float enter[4]) {
    constexpr float kFarScale = 1.0f + 2.0f * (3.0f * 0x1p-24f) / (1.0f - 3.0f * 0x1p-24f);
#if defined(__SSE2__) && !defined(__CUDA_ARCH__)
    const __m128 ox = _mm_set1_ps(ray.origin.x), oy = _mm_set1_ps(ray.origin.y), oz = _mm_set1_ps(ray.origin.z);
    const __m128 ix = _mm_set1_ps(ray.invDirection.x), iy = _mm_set1_ps(ray.invDirection.y),
                 iz = _mm_set1_ps(ray.invDirection.z);
    const __m128 t0x = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.lowerX), ox), ix);
    const __m128 t1x = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.upperX), ox), ix);
    const __m128 t0y = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.lowerY), oy), iy);
    const __m128 t1y = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.upperY), oy), iy);
    const __m128 t0z = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.lowerZ), oz), iz);
    const __m128 t1z = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.upperZ), oz), iz);
    __m128 nearX = _mm_min_ps(t0x, t1x), farX = _mm_max_ps(t0x, t1x);
    __m128 nearY = _mm_min_ps(t0y, t1y), farY = _mm_max_ps(t0y, t1y);
    __m128 nearZ = _mm_min_ps(t0z, t1z), farZ = _mm_max_ps(t0z, t1z);
    if (ParallelToAxis) {
        // Lanes where a slab distance is NaN (0·inf) do not restrict that axis.
        const __m128 lowest = _mm_set1_ps(-kInfinity), highest = _mm_set1_ps(kInfinity);
        const __m128 nanX = _mm_cmpunord_ps(t0x, t1x), nanY = _mm_cmpunord_ps(t0y, t1y),
                     nanZ = _mm_cmpunord_ps(t0z, t1z);
        nearX = _mm_or_ps(_mm_andnot_ps(nanX, nearX), _mm_and_ps(nanX, lowest));
        farX = _mm_or_ps(_mm_andnot_ps(nanX, farX), _mm_and_ps(nanX, highest));
        nearY = _mm_or_ps(_mm_andnot_ps(nanY, nearY), _mm_and_ps(nanY, lowest));
        farY = _mm_or_ps(_mm_andnot_ps(nanY, farY), _mm_and_ps(nanY, highest));
        nearZ = _mm_or_ps(_mm_andnot_ps(nanZ, nearZ), _mm_and_ps(nanZ, lowest));
        farZ = _mm_or_ps(_mm_andnot_ps(nanZ, farZ), _mm_and_ps(nanZ, highest));
    }
    const __m128 in = _mm_max_ps(_mm_max_ps(nearX, nearY), _mm_max_ps(nearZ, _mm_set1_ps(tMin)));
    const __m128 out = _mm_mul_ps(_mm_min_ps(_mm_min_ps(farX, farY), _mm_min_ps(farZ, _mm_set1_ps(tMax))),
                                  _mm_set1_ps(kFarScale));
    _mm_storeu_ps(enter, in);
    return _mm_movemask_ps(_mm_cmple_ps(in, out));
#else
    const float ox = ray.origin.x, oy = ray.origin.y, oz = ray.origin.z;
    const float ix = ray.invDirection.x, iy = ray.invDirection.y, iz = ray.invDirection.z;
    int mask = 0;
    for (int i = 0; i < 4; ++i) {
        const float t0x = (node.lowerX[i] - ox) * ix, t1x = (node.upperX[i] - ox) * ix;
        const float t0y = (node.lowerY[i] - oy) * iy, t1y = (node.upperY[i] - oy) * iy;
        const float t0z = (node.lowerZ[i] - oz) * iz, t1z = (node.upperZ[i] - oz) * iz;
        float nearX = glm::min(t0x, t1x), farX = glm::max(t0x, t1x);
        float nearY = glm::min(t0y, t1y), farY = glm::max(t0y, t1y);
        float nearZ = glm::min(t0z, t1z), farZ = glm::max(t0z, t1z);
        if (ParallelToAxis) {
            if (t0x != t0x || t1x != t1x) nearX = -kInfinity, farX = kInfinity;
            if (t0y != t0y || t1y != t1y) nearY = -kInfinity, farY = kInfinity;
            if (t0z != t0z || t1z != t1z) nearZ = -kInfinity, farZ = kInfinity;
        }
        enter[i] = glm::max(glm::max(nearX, nearY), glm::max(nearZ, tMin));
        if (enter[i] <= glm::min(glm::min(farX, farY), glm::min(farZ, tMax)) * kFarScale) mask |= 1 << i;
    }
    return mask;
#endif
}

// Deep enough for any wide tree: each level pushes at most three entries beyond the one it
// pops, and a wide tree is no deeper than its binary tree.
constexpr int kBvhWideStackSize = 3 * kBvhMaxDepth + 4;

VL_HOSTDEV inline int lowestSetBit(unsigned mask) {
#if defined(__CUDA_ARCH__)
    return __ffs(static_cast<int>(mask)) - 1;
#else
    return __builtin_ctz(mask);
#endif
}

// Lanes of a wide node that hold a child, as bits 0–3.
VL_HOSTDEV inline int occupiedLanes(const BvhWideNode& node) {
#if defined(__SSE2__) && !defined(__CUDA_ARCH__)
    const __m128i empty = _mm_cmpeq_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(node.count)),
                                          _mm_set1_epi32(-1));
    return ~_mm_movemask_ps(_mm_castsi128_ps(empty)) & 0xF;
#else
    int mask = 0;
    for (int i = 0; i < 4; ++i)
        if (node.count[i] != kBvhEmptyLane) mask |= 1 << i;
    return mask;
#endif
}

template <bool AnyHit, bool ParallelToAxis>
VL_HOSTDEV inline bool traverseWide(const BvhView& bvh, const Ray& ray, const RayBoxData& boxRay, Hit& hit) {
    const WatertightRay triRay = makeWatertightRay(ray.origin, ray.direction);
    float tMax = ray.tMax;
    bool found = false;
    struct Entry {
        uint32_t index;  // wide node, or first slot of a leaf
        uint32_t count;  // 0: wide node; else leaf triangle count
        float near;
    };
    Entry stack[kBvhWideStackSize];
    int top = 0;
    Entry current{0, 0, 0.0f};
    for (;;) {
        if (current.count == 0) {
            const BvhWideNode& node = bvh.wideNodes[current.index];
            float enter[4];
            int mask = intersectBoxes4<ParallelToAxis>(node, boxRay, ray.tMin, tMax, enter) & occupiedLanes(node);
            if (mask != 0) {
                // Visit the nearest lane next; push the others, farthest deepest.
                int lane = lowestSetBit(static_cast<unsigned>(mask));
                mask &= mask - 1;
                current = Entry{node.child[lane], node.count[lane], enter[lane]};
                if (mask == 0) continue;
                const int base = top;
                do {
                    lane = lowestSetBit(static_cast<unsigned>(mask));
                    mask &= mask - 1;
                    Entry e{node.child[lane], node.count[lane], enter[lane]};
                    if (e.near < current.near) {
                        const Entry swap = current;
                        current = e;
                        e = swap;
                    }
                    // Insert e among this node's pushed entries, sorted by decreasing near.
                    int j = top++;
                    for (; j > base && stack[j - 1].near < e.near; --j) stack[j] = stack[j - 1];
                    stack[j] = e;
                } while (mask != 0);
                continue;
            }
        } else {
            const uint32_t end = current.index + current.count;
            for (uint32_t slot = current.index; slot < end; ++slot) {
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
        }
        // Pop, skipping entries that start beyond the closest hit found since their push.
        for (;;) {
            if (top == 0) return found;
            current = stack[--top];
            if (current.near <= tMax * (1.0f + 4.0f * 0x1p-24f)) break;
        }
    }
}

template <bool AnyHit>
VL_HOSTDEV inline bool traverse(const BvhView& bvh, const Ray& ray, Hit& hit) {
    if (bvh.nodeCount == 0) return false;
    const RayBoxData boxRay = makeRayBoxData(ray);
    if (bvh.wideNodes != nullptr)
        return boxRay.parallelToAxis ? traverseWide<AnyHit, true>(bvh, ray, boxRay, hit)
                                     : traverseWide<AnyHit, false>(bvh, ray, boxRay, hit);
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
