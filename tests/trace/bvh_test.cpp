#include "core/error.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "trace/bvh.h"
#include "trace/bvh_traverse.h"
#include "trace/triangle_intersect.h"

#include <tbb/global_control.h>

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>

using namespace vl;

namespace {

SceneTriangles randomSoup(uint32_t count, uint64_t seed, float size) {
    SceneTriangles tris;
    Pcg32 rng(seed, 1);
    for (uint32_t i = 0; i < count; ++i) {
        const vec3 centre(rng.next1D(), rng.next1D(), rng.next1D());
        for (int k = 0; k < 3; ++k)
            tris.vertices.push_back(centre + size * (vec3(rng.next1D(), rng.next1D(), rng.next1D()) - 0.5f));
        tris.meshIndex.push_back(0);
        tris.localIndex.push_back(i);
    }
    return tris;
}

Ray randomRay(Pcg32& rng) {
    Ray ray;
    ray.origin = vec3(rng.next1D(), rng.next1D(), rng.next1D()) * 1.4f - 0.2f;
    ray.direction = sampleUniformSphere(vec2(rng.next1D(), rng.next1D()));
    return ray;
}

// Closest hit over every triangle, no acceleration structure.
bool bruteForceClosest(const SceneTriangles& tris, const Ray& ray, Hit& hit) {
    const WatertightRay wr = makeWatertightRay(ray.origin, ray.direction);
    bool found = false;
    float tMax = ray.tMax;
    for (uint32_t i = 0; i < tris.vertices.size() / 3; ++i) {
        TriangleHit th;
        if (intersectTriangle(wr, tris.vertices[3 * i], tris.vertices[3 * i + 1], tris.vertices[3 * i + 2], ray.tMin,
                              tMax, th)) {
            found = true;
            tMax = th.t;
            hit.t = th.t;
            hit.triangle = i;
            hit.b1 = th.b1;
            hit.b2 = th.b2;
        }
    }
    return found;
}

}  // namespace

TEST_CASE("BVH closest hit equals brute force on random triangle soups", "[trace]") {
    struct Soup {
        uint32_t count;
        float size;
    };
    uint64_t seed = 0;
    for (const Soup soup : {Soup{500, 0.2f}, Soup{6000, 0.04f}, Soup{3000, 0.1f}}) {
        ++seed;
        const SceneTriangles tris = randomSoup(soup.count, seed, soup.size);
        const Bvh bvh = Bvh::build(tris);
        REQUIRE(bvh.view().wideNodes != nullptr);
        for (const bool wide : {true, false}) {
        BvhView view = bvh.view();
        if (!wide) view.wideNodes = nullptr;  // the binary traversal
        Pcg32 rng(seed, 7);
        int hits = 0;
        for (int i = 0; i < 4000; ++i) {
            Ray ray = randomRay(rng);
            if (i % 4 == 1) ray.tMax = 0.3f;
            if (i % 4 == 2) ray.tMin = 0.1f;
            Hit expected, actual;
            const bool e = bruteForceClosest(tris, ray, expected);
            const bool a = intersectClosest(view, ray, actual);
            REQUIRE(a == e);
            REQUIRE(intersectAny(view, ray) == e);
            if (e) {
                ++hits;
                REQUIRE(actual.t == expected.t);
                REQUIRE(actual.triangle == expected.triangle);
                REQUIRE(actual.b1 == expected.b1);
                REQUIRE(actual.b2 == expected.b2);
            }
        }
        // Both outcomes must be exercised for the comparison to mean something.
        REQUIRE(hits > 300);
        REQUIRE(hits < 3900);
        }
    }
}

namespace {

struct TreeStats {
    int maxDepth = 0;
    uint32_t leaves = 0;
    uint32_t maxLeafCount = 0;
};

// Walks the flat tree, checking what the layout promises: left child = this + 1, children
// inside the parent's box, leaf triangles inside the leaf's box, every slot in one leaf.
void checkSubtree(const Bvh& bvh, uint32_t index, int depth, std::vector<int>& slotSeen, TreeStats& stats) {
    REQUIRE(index < bvh.nodes.size());
    const BvhNode& node = bvh.nodes[index];
    stats.maxDepth = std::max(stats.maxDepth, depth);
    auto contains = [](const Aabb& outer, const Aabb& inner) {
        return glm::all(glm::lessThanEqual(outer.lower, inner.lower)) &&
               glm::all(glm::greaterThanEqual(outer.upper, inner.upper));
    };
    if (node.count > 0) {
        ++stats.leaves;
        stats.maxLeafCount = std::max(stats.maxLeafCount, node.count);
        for (uint32_t slot = node.firstOrChild; slot < node.firstOrChild + node.count; ++slot) {
            REQUIRE(slot < slotSeen.size());
            ++slotSeen[slot];
            for (int k = 0; k < 3; ++k) {
                const vec3 p = bvh.vertices[3 * size_t(slot) + k];
                REQUIRE(glm::all(glm::lessThanEqual(node.bounds.lower, p)));
                REQUIRE(glm::all(glm::lessThanEqual(p, node.bounds.upper)));
            }
        }
        return;
    }
    REQUIRE(node.firstOrChild > index + 1);
    REQUIRE(contains(node.bounds, bvh.nodes[index + 1].bounds));
    REQUIRE(contains(node.bounds, bvh.nodes[node.firstOrChild].bounds));
    checkSubtree(bvh, index + 1, depth + 1, slotSeen, stats);
    checkSubtree(bvh, node.firstOrChild, depth + 1, slotSeen, stats);
}

TreeStats checkTree(const Bvh& bvh, const SceneTriangles& tris) {
    const size_t count = tris.vertices.size() / 3;
    REQUIRE(bvh.triangleIds.size() == count);
    REQUIRE(bvh.vertices.size() == 3 * count);
    // The reordered vertices are the original triangle's, slot by slot.
    std::vector<int> idSeen(count, 0);
    for (size_t slot = 0; slot < count; ++slot) {
        const uint32_t id = bvh.triangleIds[slot];
        REQUIRE(id < count);
        ++idSeen[id];
        for (int k = 0; k < 3; ++k) REQUIRE(bvh.vertices[3 * slot + k] == tris.vertices[3 * size_t(id) + k]);
    }
    for (int seen : idSeen) REQUIRE(seen == 1);
    std::vector<int> slotSeen(count, 0);
    TreeStats stats;
    checkSubtree(bvh, 0, 0, slotSeen, stats);
    for (int seen : slotSeen) REQUIRE(seen == 1);
    REQUIRE(bvh.nodes.size() == 2 * size_t(stats.leaves) - 1);  // binary: every inner node has 2 children

    // The 4-wide collapse covers the same slots once each, inside its lanes' boxes, and
    // every wide node but the root is referenced exactly once.
    std::vector<int> wideSlotSeen(count, 0), wideNodeSeen(bvh.wideNodes.size(), 0);
    for (const BvhWideNode& node : bvh.wideNodes) {
        int lanes = 0;
        for (int i = 0; i < 4; ++i) {
            if (node.count[i] == kBvhEmptyLane) continue;
            ++lanes;
            const Aabb box{vec3(node.lowerX[i], node.lowerY[i], node.lowerZ[i]),
                           vec3(node.upperX[i], node.upperY[i], node.upperZ[i])};
            if (node.count[i] == 0) {
                REQUIRE(node.child[i] < bvh.wideNodes.size());
                ++wideNodeSeen[node.child[i]];
                continue;
            }
            for (uint32_t slot = node.child[i]; slot < node.child[i] + node.count[i]; ++slot) {
                ++wideSlotSeen[slot];
                for (int k = 0; k < 3; ++k) {
                    REQUIRE(glm::all(glm::lessThanEqual(box.lower, bvh.vertices[3 * size_t(slot) + k])));
                    REQUIRE(glm::all(glm::lessThanEqual(bvh.vertices[3 * size_t(slot) + k], box.upper)));
                }
            }
        }
        REQUIRE(lanes >= (count > 1 ? 2 : 1));
    }
    for (int seen : wideSlotSeen) REQUIRE(seen == 1);
    REQUIRE(wideNodeSeen[0] == 0);
    for (size_t i = 1; i < wideNodeSeen.size(); ++i) REQUIRE(wideNodeSeen[i] == 1);
    return stats;
}

bool sameBytes(const Bvh& a, const Bvh& b) {
    return a.nodes.size() == b.nodes.size() && a.vertices.size() == b.vertices.size() &&
           a.triangleIds == b.triangleIds &&
           std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(BvhNode)) == 0 &&
           std::memcmp(a.vertices.data(), b.vertices.data(), a.vertices.size() * sizeof(vec3)) == 0 &&
           a.wideNodes.size() == b.wideNodes.size() &&
           std::memcmp(a.wideNodes.data(), b.wideNodes.data(), a.wideNodes.size() * sizeof(BvhWideNode)) == 0;
}

}  // namespace

TEST_CASE("BVH layout holds its invariants and respects the leaf size", "[trace]") {
    const SceneTriangles tris = randomSoup(20000, 5, 0.05f);
    for (const int maxLeaf : {1, 4, 8}) {
        BvhSettings settings;
        settings.maxLeafSize = maxLeaf;
        const Bvh bvh = Bvh::build(tris, settings);
        const TreeStats stats = checkTree(bvh, tris);
        REQUIRE(stats.maxLeafCount <= uint32_t(maxLeaf));
        REQUIRE(stats.maxDepth <= kBvhMaxDepth);
        // SAH on well-spread triangles gives a shallow tree: well under twice log2(n).
        REQUIRE(stats.maxDepth < 2 * 15 + 5);
        Aabb all;
        for (const vec3& p : tris.vertices) all.extend(p);
        REQUIRE(bvh.bounds().lower == all.lower);
        REQUIRE(bvh.bounds().upper == all.upper);
        REQUIRE(bvh.memoryBytes() >= bvh.nodes.size() * sizeof(BvhNode) + tris.vertices.size() * sizeof(vec3));
    }
}

TEST_CASE("BVH is byte-identical at any thread count", "[trace]") {
    // Large enough that the top nodes are binned in parallel chunks (above 65536 triangles)
    // and subtrees are built in parallel (above 4096).
    const SceneTriangles tris = randomSoup(100000, 9, 0.03f);
    std::vector<Bvh> builds;
    for (const int threads : {1, 2, 4}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        builds.push_back(Bvh::build(tris));
    }
    REQUIRE(builds[0].nodes.size() > 1000);
    checkTree(builds[0], tris);
    REQUIRE(sameBytes(builds[0], builds[1]));
    REQUIRE(sameBytes(builds[0], builds[2]));
}

TEST_CASE("Coincident triangles still give a bounded-depth correct BVH", "[trace]") {
    // 5000 copies of one triangle plus a few others: no SAH split separates the copies, so
    // the builder must split by count, not recurse forever or make a giant leaf.
    SceneTriangles tris;
    for (uint32_t i = 0; i < 5000; ++i) {
        tris.vertices.insert(tris.vertices.end(), {vec3(0, 0, 0), vec3(1, 0, 0), vec3(0, 1, 0)});
        tris.meshIndex.push_back(0);
        tris.localIndex.push_back(i);
    }
    // A long chain of ever smaller triangles: SAH splits off one at a time.
    for (uint32_t i = 0; i < 3000; ++i) {
        const float x = 2.0f + std::ldexp(1.0f, -int(i % 100)) + float(i / 100);
        tris.vertices.insert(tris.vertices.end(), {vec3(x, 0, 1), vec3(x + 0.001f, 0, 1), vec3(x, 0.001f, 1)});
        tris.meshIndex.push_back(0);
        tris.localIndex.push_back(5000 + i);
    }
    const Bvh bvh = Bvh::build(tris);
    const TreeStats stats = checkTree(bvh, tris);
    REQUIRE(stats.maxDepth <= kBvhMaxDepth);
    REQUIRE(stats.maxLeafCount <= 8u);
    Ray ray;
    ray.origin = vec3(0.25f, 0.25f, 1.0f);
    ray.direction = vec3(0, 0, -1);
    Hit hit;
    REQUIRE(intersectClosest(bvh.view(), ray, hit));
    REQUIRE(hit.t == 1.0f);
    REQUIRE(hit.triangle < 5000u);
}

TEST_CASE("An empty BVH is hit by nothing", "[trace]") {
    const Bvh bvh = Bvh::build(SceneTriangles{});
    REQUIRE(bvh.nodes.empty());
    REQUIRE(bvh.bounds().empty());
    Ray ray;
    Hit hit;
    REQUIRE_FALSE(intersectClosest(bvh.view(), ray, hit));
    REQUIRE_FALSE(intersectAny(bvh.view(), ray));
    REQUIRE(hit.triangle == ~0u);
}

TEST_CASE("BVH rejects bad settings and bad triangles with a message", "[trace]") {
    const SceneTriangles tris = randomSoup(10, 1, 0.1f);
    BvhSettings bins;
    bins.bins = 1;
    REQUIRE_THROWS_WITH(Bvh::build(tris, bins), Catch::Contains("bins = 1"));
    BvhSettings leaf;
    leaf.maxLeafSize = 0;
    REQUIRE_THROWS_AS(Bvh::build(tris, leaf), SettingsError);
    BvhSettings cost;
    cost.intersectionCost = std::nanf("");
    REQUIRE_THROWS_WITH(Bvh::build(tris, cost), Catch::Contains("intersectionCost"));
    SceneTriangles bad = tris;
    bad.vertices[7].y = std::numeric_limits<float>::infinity();
    REQUIRE_THROWS_WITH(Bvh::build(bad), Catch::Contains("triangle 2"));
}

TEST_CASE("gatherTriangles maps global ids back to mesh and local triangle", "[trace]") {
    Scene scene;
    scene.sourcePath = "two-meshes.gltf";
    Mesh a;
    a.name = "floor/0";
    a.positions = {vec3(0, 0, 0), vec3(1, 0, 0), vec3(1, 0, 1), vec3(0, 0, 1)};
    a.indices = {0, 1, 2, 0, 2, 3};
    Mesh b;
    b.name = "wall/0";
    b.positions = {vec3(0, 0, 5), vec3(1, 0, 5), vec3(0, 1, 5)};
    b.indices = {0, 1, 2};
    scene.meshes = {a, b};
    const SceneTriangles tris = gatherTriangles(scene);
    REQUIRE(tris.vertices.size() == 9);
    REQUIRE(tris.meshIndex == std::vector<uint32_t>{0, 0, 1});
    REQUIRE(tris.localIndex == std::vector<uint32_t>{0, 1, 0});
    REQUIRE(tris.vertices[3] == a.positions[0]);
    REQUIRE(tris.vertices[5] == a.positions[3]);
    REQUIRE(tris.vertices[7] == b.positions[1]);
    // Through the BVH, the wall's triangle comes back as global id 2.
    const Bvh bvh = Bvh::build(tris);
    Ray ray;
    ray.origin = vec3(0.2f, 0.2f, 0.0f);
    ray.direction = vec3(0, 0, 1);
    ray.tMin = 0.5f;
    Hit hit;
    REQUIRE(intersectClosest(bvh.view(), ray, hit));
    REQUIRE(hit.triangle == 2u);
    REQUIRE(hit.t == Approx(5.0f).epsilon(1e-6));

    scene.meshes[1].indices[2] = 7;
    REQUIRE_THROWS_WITH(gatherTriangles(scene),
                        Catch::Contains("two-meshes.gltf") && Catch::Contains("wall/0") && Catch::Contains("triangle 0") &&
                            Catch::Contains("index 7"));
}

TEST_CASE("Rays with a zero or NaN direction find nothing and terminate", "[trace]") {
    const SceneTriangles tris = randomSoup(2000, 4, 0.1f);
    const Bvh bvh = Bvh::build(tris);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (const vec3 direction : {vec3(0.0f), vec3(nan, 0.0f, 1.0f), vec3(nan)}) {
        for (const bool wide : {true, false}) {
            BvhView view = bvh.view();
            if (!wide) view.wideNodes = nullptr;
            Ray ray;
            ray.origin = vec3(0.5f);  // inside the soup
            ray.direction = direction;
            Hit hit;
            REQUIRE_FALSE(intersectClosest(view, ray, hit));
            REQUIRE(hit.triangle == ~0u);
            REQUIRE_FALSE(intersectAny(view, ray));
        }
    }
}
