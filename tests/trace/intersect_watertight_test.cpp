// Watertightness: a closed mesh has no cracks for rays, and a ray through a shared edge or
// vertex counts exactly one triangle (no gap, no double hit).
#include "core/rng.h"
#include "core/sampling.h"
#include "trace/bvh.h"
#include "trace/bvh_traverse.h"
#include "trace/triangle_intersect.h"

#include <catch2/catch.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>

#include <map>
#include <utility>

using namespace vl;

namespace {

struct IndexedMesh {
    std::vector<vec3> positions;
    std::vector<uint32_t> indices;  // counter-clockwise from outside

    SceneTriangles triangles() const {
        SceneTriangles tris;
        for (size_t t = 0; t < indices.size() / 3; ++t) {
            for (int k = 0; k < 3; ++k) tris.vertices.push_back(positions[indices[3 * t + k]]);
            tris.meshIndex.push_back(0);
            tris.localIndex.push_back(static_cast<uint32_t>(t));
        }
        return tris;
    }
    std::vector<std::pair<uint32_t, uint32_t>> edges() const {
        std::map<std::pair<uint32_t, uint32_t>, int> seen;
        for (size_t t = 0; t < indices.size() / 3; ++t)
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = indices[3 * t + k], b = indices[3 * t + (k + 1) % 3];
                ++seen[{std::min(a, b), std::max(a, b)}];
            }
        std::vector<std::pair<uint32_t, uint32_t>> out;
        for (const auto& [edge, count] : seen) {
            REQUIRE(count == 2);  // closed, manifold: every edge shared by exactly two triangles
            out.push_back(edge);
        }
        return out;
    }
};

// Unit icosphere: an icosahedron with each triangle split in four `subdivisions` times,
// midpoints projected onto the sphere (shared, so the mesh stays closed).
IndexedMesh icosphere(int subdivisions, float radius = 1.0f, vec3 centre = vec3(0.0f)) {
    const float g = (1.0f + glm::sqrt(5.0f)) * 0.5f;
    IndexedMesh m;
    std::vector<vec3> unit = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                              {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    for (vec3& p : unit) p = glm::normalize(p);
    m.indices = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
                 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (int s = 0; s < subdivisions; ++s) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoint;
        auto mid = [&](uint32_t a, uint32_t b) {
            const auto key = std::make_pair(std::min(a, b), std::max(a, b));
            auto it = midpoint.find(key);
            if (it != midpoint.end()) return it->second;
            unit.push_back(glm::normalize(unit[a] + unit[b]));
            return midpoint[key] = static_cast<uint32_t>(unit.size() - 1);
        };
        std::vector<uint32_t> next;
        for (size_t t = 0; t < m.indices.size(); t += 3) {
            const uint32_t a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
            const uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
            next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        m.indices = std::move(next);
    }
    for (const vec3& p : unit) m.positions.push_back(centre + radius * p);
    return m;
}

// Cube [-1,1]³, each face a 2×2 grid of quads split along alternating diagonals: integer
// vertices, so rays aimed at vertices and edge midpoints are exact and the edge functions
// come out exactly 0 (the tie rule decides).
IndexedMesh gridCube() {
    IndexedMesh m;
    std::map<std::tuple<int, int, int>, uint32_t> index;
    auto vertex = [&](int x, int y, int z) {
        const auto key = std::make_tuple(x, y, z);
        auto it = index.find(key);
        if (it != index.end()) return it->second;
        m.positions.push_back(vec3(float(x), float(y), float(z)));
        return index[key] = static_cast<uint32_t>(m.positions.size() - 1);
    };
    for (int axis = 0; axis < 3; ++axis)
        for (int side : {-1, 1}) {
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            auto at = [&](int a, int b) {
                int p[3];
                p[axis] = side;
                p[u] = a;
                p[v] = b;
                return vertex(p[0], p[1], p[2]);
            };
            for (int a = -1; a < 1; ++a)
                for (int b = -1; b < 1; ++b) {
                    // (u, v, axis) is right-handed, so (a,b)→(a+1,b)→(a+1,b+1) is CCW seen
                    // from +axis: keep it for side +1, reverse for side −1.
                    uint32_t q[4] = {at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)};
                    if (side < 0) std::swap(q[1], q[3]);
                    if ((a + b) & 1) {
                        m.indices.insert(m.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
                    } else {
                        m.indices.insert(m.indices.end(), {q[1], q[2], q[3], q[1], q[3], q[0]});
                    }
                }
        }
    return m;
}

// The same tree walked through its binary nodes instead of the 4-wide ones.
BvhView binaryView(const Bvh& bvh) {
    BvhView view = bvh.view();
    view.wideNodes = nullptr;
    return view;
}

int bruteForceHitCount(const SceneTriangles& tris, const Ray& ray) {
    const WatertightRay wr = makeWatertightRay(ray.origin, ray.direction);
    int count = 0;
    for (size_t t = 0; t < tris.vertices.size() / 3; ++t) {
        TriangleHit hit;
        count += intersectTriangle(wr, tris.vertices[3 * t], tris.vertices[3 * t + 1], tris.vertices[3 * t + 2],
                                   ray.tMin, ray.tMax, hit);
    }
    return count;
}

}  // namespace

TEST_CASE("A million random rays from inside a closed icosphere all hit", "[trace]") {
    const IndexedMesh sphere = icosphere(4);
    REQUIRE(sphere.indices.size() / 3 == 5120);
    const Bvh bvh = Bvh::build(sphere.triangles());
    const BvhView view = bvh.view();
    // The icosphere is inscribed in the unit sphere; its inradius is above 0.99 at this level.
    std::atomic<int> misses{0}, anyMisses{0}, outOfRange{0};
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, 1000000, 10000), [&](const tbb::blocked_range<uint32_t>& range) {
        for (uint32_t i = range.begin(); i != range.end(); ++i) {
            Pcg32 rng = Pcg32::forItem(i, 0);
            Ray ray;
            ray.origin =
                0.98f * glm::pow(rng.next1D(), 1.0f / 3.0f) * sampleUniformSphere(vec2(rng.next1D(), rng.next1D()));
            ray.direction = sampleUniformSphere(vec2(rng.next1D(), rng.next1D()));
            // Every tenth ray is axis-aligned or diagonal: zero direction components.
            if (i % 10 == 0)
                ray.direction = glm::normalize(vec3(float(i / 10 % 3) - 1.0f, float(i / 30 % 3) - 1.0f, 1.0f));
            Hit hit;
            if (!intersectClosest(view, ray, hit)) {
                ++misses;
                continue;
            }
            if (!intersectAny(view, ray)) ++anyMisses;
            const float r = glm::length(ray.at(hit.t));
            if (!(r > 0.99f && r < 1.0001f)) ++outOfRange;
        }
    });
    REQUIRE(misses.load() == 0);
    REQUIRE(anyMisses.load() == 0);
    REQUIRE(outOfRange.load() == 0);
}

TEST_CASE("Rays through shared vertices and edges of an icosphere hit exactly one triangle", "[trace]") {
    const IndexedMesh sphere = icosphere(3);
    const SceneTriangles tris = sphere.triangles();
    const Bvh bvh = Bvh::build(tris);
    const std::vector<vec3> origins = {vec3(0.0f), vec3(0.1f, -0.2f, 0.3f), vec3(-0.5f, 0.25f, 0.125f)};
    std::vector<vec3> targets = sphere.positions;
    for (const auto& [a, b] : sphere.edges()) {
        targets.push_back(0.5f * (sphere.positions[a] + sphere.positions[b]));
        // A point a quarter along the edge too: not symmetric between the two triangles.
        targets.push_back(0.75f * sphere.positions[a] + 0.25f * sphere.positions[b]);
    }
    int checked = 0;
    for (const vec3& origin : origins)
        for (const vec3& target : targets) {
            Ray ray;
            ray.origin = origin;
            ray.direction = target - origin;  // not normalised: t = 1 at the target
            REQUIRE(bruteForceHitCount(tris, ray) == 1);
            for (const BvhView& view : {bvh.view(), binaryView(bvh)}) {
                Hit hit;
                REQUIRE(intersectClosest(view, ray, hit));
                REQUIRE(hit.t == Approx(1.0f).margin(1e-5));
            }
            ++checked;
        }
    REQUIRE(checked == 3 * (642 + 2 * 1920));
}

TEST_CASE("Rays exactly through vertices and edges of an integer cube hit exactly one triangle", "[trace]") {
    const IndexedMesh cube = gridCube();
    REQUIRE(cube.edges().size() == 72);  // 6 faces × 8 triangles × 3 / 2
    const SceneTriangles tris = cube.triangles();
    const Bvh bvh = Bvh::build(tris);
    // Half-integer targets on the surface include every vertex, edge midpoint and the
    // middle of every diagonal; the origins keep the ray's shear exact (powers of two).
    const std::vector<vec3> origins = {vec3(0.0f), vec3(0.5f, 0.0f, 0.0f), vec3(-0.5f, 0.5f, 0.25f)};
    int checked = 0, axisParallel = 0;
    for (const vec3& origin : origins)
        for (int x = -2; x <= 2; ++x)
            for (int y = -2; y <= 2; ++y)
                for (int z = -2; z <= 2; ++z) {
                    const vec3 target(0.5f * float(x), 0.5f * float(y), 0.5f * float(z));
                    if (maxComponent(glm::abs(target)) != 1.0f) continue;  // on the surface only
                    for (int flip = 0; flip < 2; ++flip) {
                        Ray ray;
                        ray.origin = origin;
                        ray.direction = target - origin;
                        if (flip) {
                            // The same line, started outside and pointing in: −0 components.
                            ray.origin = origin + 4.0f * ray.direction;
                            ray.direction = -ray.direction;
                            ray.tMax = 3.5f;  // stop before the far side of the cube
                        }
                        axisParallel += ray.direction.x == 0.0f || ray.direction.y == 0.0f || ray.direction.z == 0.0f;
                        INFO("origin " << ray.origin.x << " " << ray.origin.y << " " << ray.origin.z << " dir "
                                       << ray.direction.x << " " << ray.direction.y << " " << ray.direction.z);
                        REQUIRE(bruteForceHitCount(tris, ray) == 1);
                        for (const BvhView& view : {bvh.view(), binaryView(bvh)}) {
                            Hit hit;
                            REQUIRE(intersectClosest(view, ray, hit));
                            REQUIRE(hit.t == Approx(flip ? 3.0f : 1.0f).epsilon(1e-6));
                            REQUIRE(intersectAny(view, ray));
                        }
                        ++checked;
                    }
                }
    REQUIRE(checked == 3 * 2 * 98);  // 5³ − 3³ half-integer points on the surface
    REQUIRE(axisParallel > 100);
}
