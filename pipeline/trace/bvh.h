// Bounding volume hierarchy over the scene's world-space triangles: binned SAH build
// (ERRATA eq. 9) into a flat node array; traversal is VL_HOSTDEV over BvhView so the CUDA
// launchers reuse it.
#pragma once

#include "core/aabb.h"
#include "core/ray.h"
#include "scene/scene.h"

#include <cstdint>
#include <vector>

namespace vl {

// Every triangle of a Scene in one array, mesh-major, so a global triangle id maps back
// to (mesh, local triangle) and from there to UVs, normals and material.
struct SceneTriangles {
    std::vector<vec3> vertices;         // 3 per triangle, world space
    std::vector<uint32_t> meshIndex;    // per triangle
    std::vector<uint32_t> localIndex;   // per triangle: index within its mesh
};

SceneTriangles gatherTriangles(const Scene& scene);

struct Hit {
    float t = kInfinity;
    uint32_t triangle = ~0u;  // global triangle id
    float b1 = 0.0f;          // barycentrics: point = (1-b1-b2)·v0 + b1·v1 + b2·v2
    float b2 = 0.0f;
};

struct BvhNode {
    Aabb bounds;
    uint32_t firstOrChild;  // leaf: first index into the triangle order; inner: right child
    uint32_t count;         // leaf: triangle count (> 0); inner: 0 (left child is this + 1)
};

// [added by bvh] The same tree collapsed to four children per node, boxes stored by axis
// so one slab test covers all four (SIMD on the CPU, a short loop on the GPU): what
// traversal uses when present. Lanes past the node's children have count kBvhEmptyLane.
struct alignas(16) BvhWideNode {
    float lowerX[4], upperX[4], lowerY[4], upperY[4], lowerZ[4], upperZ[4];
    uint32_t child[4];  // inner lane: wide node index; leaf lane: first slot
    uint32_t count[4];  // inner lane: 0; leaf lane: triangle count; unused lane: kBvhEmptyLane
};
constexpr uint32_t kBvhEmptyLane = 0xFFFFFFFFu;

// Plain pointers into a built Bvh: what kernels (host or device) traverse.
struct BvhView {
    const BvhNode* nodes = nullptr;
    const vec3* vertices = nullptr;    // reordered, 3 per leaf slot
    const uint32_t* triangleIds = nullptr;  // leaf slot → global triangle id
    uint32_t nodeCount = 0;
    // [added by bvh] Optional: null → traversal walks the binary `nodes` instead (same hits).
    const BvhWideNode* wideNodes = nullptr;
    uint32_t wideNodeCount = 0;
    // The largest side of the root's box (1 for an empty tree): the scale of ray offsets
    // (ray_offset.h), so they are the same fraction of a 1 mm scene as of a 1 km one.
    float extent = 1.0f;
};

// The deepest tree Bvh::build makes (it falls back to object-median splits to stay within
// it), so traversal can use a fixed stack. [added by bvh]
constexpr int kBvhMaxDepth = 60;

struct BvhSettings {
    int bins = 16;
    int maxLeafSize = 8;
    float traversalCost = 1.0f;
    float intersectionCost = 1.0f;
};

class Bvh {
public:
    static Bvh build(const SceneTriangles& triangles, const BvhSettings& settings = {});

    BvhView view() const;
    size_t memoryBytes() const;
    const Aabb& bounds() const;

    std::vector<BvhNode> nodes;
    std::vector<vec3> vertices;
    std::vector<uint32_t> triangleIds;
    std::vector<BvhWideNode> wideNodes;  // [added by bvh] nodes collapsed 4-wide
};

// Traversal (closest hit, any hit) is inline VL_HOSTDEV in trace/bvh_traverse.h, so CUDA
// compiles it without relocatable device code.

}  // namespace vl
