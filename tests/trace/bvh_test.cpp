#include "core/error.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "trace/bvh.h"
#include "trace/bvh_traverse.h"
#include "trace/triangle_intersect.h"

#include <tbb/global_control.h>

#include <catch2/catch.hpp>

#include <cstring>

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
        const BvhView view = bvh.view();
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
