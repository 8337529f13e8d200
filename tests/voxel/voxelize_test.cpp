// Voxelization: the conservative voxel set against a brute-force separating axis test, hand
// counted quads, conservation of area, exact uniform colours, outward normals, scale
// invariance, no NaN, thread-count independence, settings validation and interior filling.
// Scenes are built in code.
#include "core/error.h"
#include "core/rng.h"
#include "scene/gltf_loader.h"
#include "support/paths.h"
#include "voxel/triangle_box.h"
#include "voxel/voxelize.h"

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <tuple>

using namespace vl;

namespace {

using VoxelSet = std::set<std::tuple<int, int, int>>;

std::tuple<int, int, int> tupleOf(const ivec3& c) { return {c.x, c.y, c.z}; }

Mesh meshOf(const std::vector<vec3>& positions, int material = -1, std::string name = "mesh") {
    Mesh mesh;
    mesh.name = std::move(name);
    mesh.material = material;
    mesh.positions = positions;
    for (uint32_t i = 0; i < positions.size(); ++i) mesh.indices.push_back(i);
    return mesh;
}

Scene sceneOf(std::vector<Mesh> meshes, std::vector<Material> materials = {}) {
    Scene scene;
    scene.sourcePath = "test.gltf";
    scene.meshes = std::move(meshes);
    scene.materials = std::move(materials);
    return scene;
}

Material colouredMaterial(vec3 colour) {
    Material m;
    m.name = "coloured";
    m.baseColorFactor = vec4(colour, 1.0f);
    return m;
}

// Icosphere with outward (counter-clockwise) triangles, as an indexed mesh.
Mesh icosphere(vec3 centre, float radius, int subdivisions, int material = -1) {
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    std::vector<vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                           {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    std::vector<uint32_t> f = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4,
                               11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8,
                               3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (vec3& p : v) p = glm::normalize(p);
    for (int s = 0; s < subdivisions; ++s) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            const auto key = std::minmax(a, b);
            auto it = midpoints.find(key);
            if (it != midpoints.end()) return it->second;
            v.push_back(glm::normalize(v[a] + v[b]));
            return midpoints[key] = static_cast<uint32_t>(v.size() - 1);
        };
        std::vector<uint32_t> next;
        for (size_t i = 0; i < f.size(); i += 3) {
            const uint32_t a = f[i], b = f[i + 1], c = f[i + 2];
            const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        f = std::move(next);
    }
    Mesh mesh;
    mesh.name = "icosphere";
    mesh.material = material;
    for (const vec3& p : v) mesh.positions.push_back(centre + radius * p);
    mesh.indices = f;
    return mesh;
}

double meshArea(const Scene& scene) {
    double area = 0.0;
    for (const Mesh& mesh : scene.meshes)
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            const dvec3 a(mesh.positions[mesh.indices[3 * t]]), b(mesh.positions[mesh.indices[3 * t + 1]]),
                c(mesh.positions[mesh.indices[3 * t + 2]]);
            area += 0.5 * glm::length(glm::cross(b - a, c - a));
        }
    return area;
}

dvec3 unitNormal(const dvec3& a, const dvec3& b, const dvec3& c) { return glm::normalize(glm::cross(b - a, c - a)); }

VoxelSet walkSet(const dvec3& a, const dvec3& b, const dvec3& c) {
    VoxelSet set;
    forEachVoxelPiece(a, b, c, unitNormal(a, b, c), [&](const ivec3& v, const ClipPolygon&, double) {
        REQUIRE(set.insert(tupleOf(v)).second);  // each voxel once
    });
    return set;
}

// Every voxel whose closed box the triangle overlaps, testing all voxels around its bounds.
VoxelSet bruteForceSat(const dvec3& a, const dvec3& b, const dvec3& c) {
    const dvec3 lo = glm::floor(glm::min(a, glm::min(b, c))) - 1.0;
    const dvec3 hi = glm::ceil(glm::max(a, glm::max(b, c))) + 1.0;
    VoxelSet set;
    for (int i = int(lo.x); i <= int(hi.x); ++i)
        for (int j = int(lo.y); j <= int(hi.y); ++j)
            for (int k = int(lo.z); k <= int(hi.z); ++k) {
                const dvec3 centre(i, j, k);
                if (triangleBoxOverlap(a - centre, b - centre, c - centre, 0.5)) set.insert({i, j, k});
            }
    return set;
}

// Area of the triangle inside the closed box of voxel v, clipped by all six planes at once.
double closedPieceArea(const dvec3& a, const dvec3& b, const dvec3& c, const std::tuple<int, int, int>& v) {
    ClipPolygon p = ClipPolygon::triangle(a, b, c);
    const dvec3 centre(std::get<0>(v), std::get<1>(v), std::get<2>(v));
    for (int axis = 0; axis < 3; ++axis) p = clipSlab(p, axis, centre[axis] - 0.5, centre[axis] + 0.5);
    return p.count < 3 ? 0.0 : polygonArea(p, unitNormal(a, b, c));
}

bool allFinite(const VoxelScene& v) {
    for (size_t i = 0; i < v.size(); ++i) {
        if (!isFinite(v.albedo[i]) || !isFinite(v.normal[i]) || !isFinite(v.opacity[i])) return false;
        if (!v.emission.empty() && !isFinite(v.emission[i])) return false;
        for (float w : v.axisWeights[i])
            if (!isFinite(w)) return false;
    }
    return true;
}

template <typename T>
bool sameBytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

}  // namespace

TEST_CASE("Separating axis test on hand-made touching and separated cases", "[voxel]") {
    const double gap = std::ldexp(1.0, -20);
    // A vertex exactly on the face x = ½ touches; moved out by a hair it does not.
    CHECK(triangleBoxOverlap({0.5, 0, 0}, {2, 1, 0}, {2, -1, 0.5}, 0.5));
    CHECK_FALSE(triangleBoxOverlap({0.5 + gap, 0, 0}, {2, 1, 0}, {2, -1, 0.5}, 0.5));
    // Only the plane x + y + z = c separates: at c = 1.5 the plane meets the corner (½, ½, ½).
    CHECK(triangleBoxOverlap({1.5, 0, 0}, {0, 1.5, 0}, {0, 0, 1.5}, 0.5));
    CHECK_FALSE(triangleBoxOverlap({1.5 + gap, 0, 0}, {0, 1.5 + gap, 0}, {0, 0, 1.5 + gap}, 0.5));
    // Only Z × edge separates: the triangle lies in x + y − z = 1 + 2δ, which cuts the box,
    // and its bounding box overlaps the box; for δ = 0 its edge passes through (½, ½, 0).
    for (double delta : {0.0, gap}) {
        const dvec3 a(1.5 + delta, -0.5 + delta, 0), b(-0.5 + delta, 1.5 + delta, 0), c(3, 3, 5 - 2 * delta);
        CHECK(triangleBoxOverlap(a, b, c, 0.5) == (delta == 0.0));
    }
    // A triangle far smaller than the box, inside it.
    CHECK(triangleBoxOverlap({0.1, 0.1, 0.1}, {0.1 + 1e-6, 0.1, 0.1}, {0.1, 0.1 + 1e-6, 0.1}, 0.5));
}

TEST_CASE("A triangle's voxel set equals a brute-force separating axis test", "[voxel]") {
    Pcg32 rng(2024, 7);
    auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * double(rng.next1D()); };
    auto randomPoint = [&](double extent) {
        return dvec3(vec3(float(uniform(-extent, extent)), float(uniform(-extent, extent)), float(uniform(-extent, extent))));
    };
    auto halfGrid = [&](int extent) {  // a point on voxel faces, edges and corners: multiples of ½
        return dvec3(0.5 * int(uniform(-2 * extent, 2 * extent)), 0.5 * int(uniform(-2 * extent, 2 * extent)),
                     0.5 * int(uniform(-2 * extent, 2 * extent)));
    };
    int generic = 0, exactTies = 0, tieExclusions = 0;
    for (int n = 0; n < 600; ++n) {
        dvec3 a, b, c;
        bool onGrid = false;
        switch (n % 6) {
            case 0:  // generic
                a = randomPoint(4), b = randomPoint(4), c = randomPoint(4);
                break;
            case 1: {  // sliver: the third vertex a hair off the long edge
                a = randomPoint(4), b = randomPoint(4);
                const dvec3 offset = dvec3(vec3(float(uniform(-1, 1)), float(uniform(-1, 1)), float(uniform(-1, 1)))) * 1e-4;
                c = dvec3(vec3(0.3 * a + 0.7 * b + offset));
                break;
            }
            case 2: {  // axis-aligned, in a plane between faces
                const int axis = n % 3;
                const double level = float(uniform(-3, 3));
                a = randomPoint(4), b = randomPoint(4), c = randomPoint(4);
                a[axis] = b[axis] = c[axis] = level;
                break;
            }
            case 3: {  // lying exactly in a voxel face plane
                const int axis = n % 3;
                const double level = 0.5 + int(uniform(-3, 3));
                a = randomPoint(4), b = randomPoint(4), c = randomPoint(4);
                a[axis] = b[axis] = c[axis] = level;
                onGrid = true;
                break;
            }
            case 4:  // vertices on voxel faces, edges and corners
                a = halfGrid(3), b = halfGrid(3), c = halfGrid(3);
                onGrid = true;
                break;
            default:  // much smaller than a voxel
                a = randomPoint(4);
                b = a + dvec3(vec3(float(uniform(0, 1e-3)), float(uniform(0, 1e-3)), 0));
                c = a + dvec3(vec3(0, float(uniform(0, 1e-3)), float(uniform(0, 1e-3))));
                break;
        }
        if (!(glm::length(glm::cross(b - a, c - a)) > 0.0)) continue;
        const VoxelSet walk = walkSet(a, b, c);
        const VoxelSet sat = bruteForceSat(a, b, c);
        CAPTURE(n, a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z);
        REQUIRE(!walk.empty());
        for (const auto& v : walk) REQUIRE(sat.count(v) == 1);
        if (!onGrid) {
            REQUIRE(walk == sat);
            ++generic;
            continue;
        }
        // Exact ties: a voxel the SAT touches is left out only when the triangle meets its
        // box in no area, or lies in its face plane and the voxel is the one in front.
        ++exactTies;
        const dvec3 normal = unitNormal(a, b, c);
        for (const auto& v : sat) {
            if (walk.count(v)) continue;
            ++tieExclusions;
            const double area = closedPieceArea(a, b, c, v);
            if (area == 0.0) continue;
            bool inFrontOnFace = false;
            for (int axis = 0; axis < 3; ++axis) {
                if (a[axis] != b[axis] || a[axis] != c[axis]) continue;
                const int voxel = std::get<0>(v) * (axis == 0) + std::get<1>(v) * (axis == 1) + std::get<2>(v) * (axis == 2);
                inFrontOnFace = normal[axis] > 0 ? voxel - 0.5 == a[axis] : voxel + 0.5 == a[axis];
            }
            REQUIRE(inFrontOnFace);
        }
    }
    CHECK(generic > 350);
    CHECK(exactTies > 150);
    CHECK(tieExclusions > 0);  // the tie rules were exercised
}

TEST_CASE("voxelize gives one triangle's walk set as its voxels", "[voxel]") {
    Pcg32 rng(99, 1);
    for (int n = 0; n < 50; ++n) {
        std::vector<vec3> p(3);
        for (vec3& v : p) v = vec3(rng.next1D(), rng.next1D(), rng.next1D()) * 8.0f - 4.0f;
        VoxelSettings settings;
        settings.voxelSize = 1.0;
        const VoxelScene voxels = voxelize(sceneOf({meshOf(p)}), settings);
        const VoxelSet expected = bruteForceSat(dvec3(p[0]), dvec3(p[1]), dvec3(p[2]));
        VoxelSet got;
        for (const ivec3& c : voxels.coords) got.insert(tupleOf(c));
        REQUIRE(got == expected);
        REQUIRE(std::is_sorted(voxels.coords.begin(), voxels.coords.end(), [](const ivec3& a, const ivec3& b) {
            return tupleOf(a) < tupleOf(b);
        }));
    }
}

TEST_CASE("An axis-aligned quad covers exactly the voxels counted by hand", "[voxel]") {
    // In voxel units the quad spans x ∈ [0.2, 3.7], y ∈ [−0.6, 1.1] at z = 0.3: voxels
    // i = 0..4 overlap x by 0.3, 1, 1, 1, 0.2 and j = −1..1 overlap y by 0.1, 1, 0.6.
    const float h = 0.25f;
    auto quad = [&](float z, bool flip) {
        const vec3 p00(0.2f, -0.6f, z), p10(3.7f, -0.6f, z), p11(3.7f, 1.1f, z), p01(0.2f, 1.1f, z);
        std::vector<vec3> tris = flip ? std::vector<vec3>{p00, p11, p10, p00, p01, p11}
                                      : std::vector<vec3>{p00, p10, p11, p00, p11, p01};
        for (vec3& v : tris) v *= h;
        return sceneOf({meshOf(tris)});
    };
    const std::map<int, double> xOverlap = {{0, 0.3}, {1, 1}, {2, 1}, {3, 1}, {4, 0.2}};
    const std::map<int, double> yOverlap = {{-1, 0.1}, {0, 1}, {1, 0.6}};
    VoxelSettings settings;
    settings.voxelSize = h;

    // Between faces (z = 0.3 → k = 0), and exactly on the face z = ½: the voxel behind it
    // (k = 0 for a +z normal, k = 1 for −z).
    for (const auto& [z, flip, layer] : {std::tuple<float, bool, int>{0.3f, false, 0}, {0.3f, true, 0},
                                         {0.5f, false, 0}, {0.5f, true, 1}}) {
        CAPTURE(z, flip);
        VoxelizeStats stats;
        const VoxelScene voxels = voxelize(quad(z, flip), settings, nullptr, &stats);
        REQUIRE(voxels.size() == 15);
        int solid = 0;
        for (size_t v = 0; v < voxels.size(); ++v) {
            const ivec3 c = voxels.coords[v];
            REQUIRE(c.z == layer);
            REQUIRE(xOverlap.count(c.x) == 1);
            REQUIRE(yOverlap.count(c.y) == 1);
            CHECK(voxels.opacity[v] == Approx(xOverlap.at(c.x) * yOverlap.at(c.y)).epsilon(1e-5));
            CHECK(voxels.normal[v] == vec3(0, 0, flip ? -1 : 1));
            const AxisWeights expectedWeights = {0, 0, 0, 0, flip ? 0.0f : voxels.opacity[v], flip ? voxels.opacity[v] : 0.0f};
            for (int f = 0; f < 6; ++f) CHECK(voxels.axisWeights[v][f] == Approx(expectedWeights[f]).margin(1e-6));
            // Where the surface lies in the voxel: the middle of its overlap on x and y, z − k.
            const double xMid = 0.5 * (std::max(0.2, c.x - 0.5) + std::min(3.7, c.x + 0.5));
            const double yMid = 0.5 * (std::max(-0.6, c.y - 0.5) + std::min(1.1, c.y + 0.5));
            CHECK(voxels.surfaceOffset[v].x == Approx(xMid - c.x).margin(1e-5));
            CHECK(voxels.surfaceOffset[v].y == Approx(yMid - c.y).margin(1e-5));
            CHECK(voxels.surfaceOffset[v].z == Approx(z - layer).margin(1e-5));
            solid += voxels.solid[v];
        }
        CHECK(solid == 3);  // i = 1..3 at j = 0
        CHECK(stats.surfaceArea == Approx(3.5 * 1.7 * h * h).epsilon(1e-5));
    }
}

TEST_CASE("Voxel piece areas sum to the mesh area", "[voxel]") {
    Pcg32 rng(5, 5);
    std::vector<vec3> soup;
    for (int i = 0; i < 300; ++i) soup.push_back(vec3(rng.next1D(), rng.next1D(), rng.next1D()) * 2.0f);
    const Scene sphere = sceneOf({icosphere(vec3(0.13f, -0.41f, 0.27f), 1.0f, 3)});
    const Scene soupScene = sceneOf({meshOf(soup)});
    for (const Scene* scene : {&sphere, &soupScene})
        for (int resolution : {7, 32, 100}) {
            VoxelSettings settings;
            settings.resolution = resolution;
            VoxelizeStats stats;
            const VoxelScene voxels = voxelize(*scene, settings, nullptr, &stats);
            CAPTURE(resolution);
            CHECK(stats.surfaceArea == Approx(meshArea(*scene)).epsilon(1e-5));
            // Clamping α at 1 only loses area.
            double clamped = 0.0;
            for (float a : voxels.opacity) clamped += a;
            CHECK(clamped * voxels.voxelSize * voxels.voxelSize <= stats.surfaceArea * (1 + 1e-6));
        }
}

TEST_CASE("A uniformly coloured mesh gives exactly that colour in every voxel", "[voxel]") {
    const vec3 red(0.63f, 0.065f, 0.05f);
    VoxelSettings settings;
    settings.resolution = 40;

    Scene plain = sceneOf({icosphere(vec3(0.1f), 1.0f, 3, 0)}, {colouredMaterial(red)});
    const VoxelScene a = voxelize(plain, settings);
    REQUIRE(a.size() > 100);
    for (const vec3& albedo : a.albedo) REQUIRE(albedo == red);

    // The same colour as per-vertex COLOR_0 (× a white factor).
    Scene painted = sceneOf({icosphere(vec3(0.1f), 1.0f, 3, 0)}, {colouredMaterial(vec3(1.0f))});
    painted.meshes[0].colors.assign(painted.meshes[0].positions.size(), vec4(red, 1.0f));
    const VoxelScene b = voxelize(painted, settings);
    REQUIRE(b.coords == a.coords);
    for (const vec3& albedo : b.albedo) REQUIRE(albedo == red);
}

TEST_CASE("Vertex colours are averaged over the area each voxel covers", "[voxel]") {
    // A quad x ∈ [0.2, 3.7], y ∈ [−0.6, 1.1] (voxel units, z = 0.3) whose red channel is
    // x / 4 and green (y + 1) / 4, linear over it: a voxel's mean colour is the colour at the
    // centroid of the rectangle it covers, e.g. voxel 0 covers x ∈ [0.2, 0.5], mean x 0.35.
    const float h = 0.5f;
    const vec3 p[4] = {{0.2f, -0.6f, 0.3f}, {3.7f, -0.6f, 0.3f}, {3.7f, 1.1f, 0.3f}, {0.2f, 1.1f, 0.3f}};
    Mesh mesh;
    mesh.name = "ramp";
    mesh.material = 0;
    for (const vec3& v : p) {
        mesh.positions.push_back(v * h);
        mesh.colors.push_back(vec4(v.x / 4.0f, (v.y + 1.0f) / 4.0f, 0.5f, 1.0f));
    }
    mesh.indices = {0, 1, 2, 0, 2, 3};
    VoxelSettings settings;
    settings.voxelSize = h;
    const VoxelScene voxels = voxelize(sceneOf({mesh}, {colouredMaterial(vec3(1.0f))}), settings);
    REQUIRE(voxels.size() == 15);
    for (size_t v = 0; v < voxels.size(); ++v) {
        const ivec3 c = voxels.coords[v];
        const double x = 0.5 * (std::max(c.x - 0.5, 0.2) + std::min(c.x + 0.5, 3.7));
        const double y = 0.5 * (std::max(c.y - 0.5, -0.6) + std::min(c.y + 0.5, 1.1));
        CAPTURE(c.x, c.y);
        CHECK(voxels.albedo[v].x == Approx(x / 4).epsilon(1e-5));
        CHECK(voxels.albedo[v].y == Approx((y + 1) / 4).epsilon(1e-5));
        CHECK(voxels.albedo[v].z == Approx(0.5).epsilon(1e-6));
    }
}

TEST_CASE("A texture is averaged over the piece and not read at its vertices", "[voxel]") {
    // One voxel-sized quad, black where x < 0 and white where x > 0 (one period of a
    // two-texel nearest texture, repeated): every vertex of the quad sees black (u = 0 and
    // u = 1 wrap to texel 0), so sampling at the vertices would give 0; the mean is ½.
    Texture stripes;
    stripes.name = "stripes";
    stripes.image = Image(2, 1, 4, 1.0f);
    stripes.image.setRgb(0, 0, vec3(0.0f));
    stripes.nearest = true;
    Material material = colouredMaterial(vec3(1.0f));
    material.baseColorTexture.texture = 0;
    Mesh mesh;
    mesh.name = "striped quad";
    mesh.material = 0;
    mesh.positions = {{-0.5f, -0.5f, 0.3f}, {0.5f, -0.5f, 0.3f}, {0.5f, 0.5f, 0.3f}, {-0.5f, 0.5f, 0.3f}};
    for (const vec3& p : mesh.positions) mesh.uv0.push_back(vec2(p.x + 0.5f, 0.5f));
    mesh.indices = {0, 1, 2, 0, 2, 3};
    Scene scene = sceneOf({mesh}, {material});
    scene.textures = {stripes};
    VoxelSettings settings;
    settings.voxelSize = 1.0;
    const VoxelScene voxels = voxelize(scene, settings);
    REQUIRE(voxels.size() == 1);
    CHECK(voxels.albedo[0].x == Approx(0.5f).margin(0.05f));
    CHECK(voxels.albedo[0].x == voxels.albedo[0].z);
    CHECK(voxels.opacity[0] == Approx(1.0f).epsilon(1e-6));
}

TEST_CASE("Alpha masks and transmission reduce coverage", "[voxel]") {
    // One voxel-sized quad: opaque → α = 1; BLEND at alpha ¼ → ¼; MASK below the cutoff →
    // no voxel; half transmissive → ½.
    auto coverage = [](Material material) {
        Mesh mesh;
        mesh.name = "quad";
        mesh.material = 0;
        mesh.positions = {{-0.5f, -0.5f, 0.3f}, {0.5f, -0.5f, 0.3f}, {0.5f, 0.5f, 0.3f}, {-0.5f, 0.5f, 0.3f}};
        mesh.indices = {0, 1, 2, 0, 2, 3};
        VoxelSettings settings;
        settings.voxelSize = 1.0;
        const VoxelScene voxels = voxelize(sceneOf({mesh}, {material}), settings);
        return voxels.size() == 1 ? double(voxels.opacity[0]) : -double(voxels.size());
    };
    Material m = colouredMaterial(vec3(0.5f));
    CHECK(coverage(m) == Approx(1.0));
    m.alphaMode = AlphaMode::Blend;
    m.baseColorFactor.w = 0.25f;
    CHECK(coverage(m) == Approx(0.25));
    m.alphaMode = AlphaMode::Mask;
    CHECK(coverage(m) == 0.0);  // no voxel at all
    m = colouredMaterial(vec3(0.5f));
    m.transmission = 0.5f;
    CHECK(coverage(m) == Approx(0.5));
}

TEST_CASE("Icosphere voxel normals point outward", "[voxel]") {
    const vec3 centre(0.3f, -0.2f, 0.7f);
    for (bool doubleSided : {false, true}) {
        Material material = colouredMaterial(vec3(0.5f));
        material.doubleSided = doubleSided;
        const Scene scene = sceneOf({icosphere(centre, 2.0f, 4, 0)}, {material});
        VoxelSettings settings;
        settings.resolution = 48;
        const VoxelScene voxels = voxelize(scene, settings);
        REQUIRE(voxels.size() > 1000);
        for (size_t v = 0; v < voxels.size(); ++v) {
            const vec3 outward = voxels.centre(v) - centre;
            REQUIRE(glm::dot(voxels.normal[v], outward) > 0.0f);
            REQUIRE(glm::length(voxels.normal[v]) == Approx(1.0f).epsilon(1e-5));
            const AxisWeights& w = voxels.axisWeights[v];
            if (doubleSided) {
                for (int a = 0; a < 3; ++a) REQUIRE(w[2 * a] == w[2 * a + 1]);  // both faces of the sheet
            } else {
                // The signed differences of the six weights are the area-weighted normal sum.
                const vec3 net(w[0] - w[1], w[2] - w[3], w[4] - w[5]);
                REQUIRE(glm::dot(glm::normalize(net), voxels.normal[v]) == Approx(1.0f).epsilon(1e-4));
            }
        }
    }
}

TEST_CASE("Scaling the scene by 1e-3 and 1e3 keeps the voxel coordinates", "[voxel]") {
    Pcg32 rng(17, 3);
    std::vector<vec3> soup;
    for (int i = 0; i < 90; ++i) soup.push_back(vec3(rng.next1D(), rng.next1D(), rng.next1D()) * 3.0f - 1.0f);
    auto scaled = [&](float s) {
        Mesh sphere = icosphere(vec3(0.37f, 0.11f, -0.23f), 1.3f, 3);
        Mesh triangles = meshOf(soup);
        for (vec3& p : sphere.positions) p *= s;
        for (vec3& p : triangles.positions) p *= s;
        return sceneOf({sphere, triangles});
    };
    VoxelSettings settings;
    settings.resolution = 37;
    const VoxelScene unit = voxelize(scaled(1.0f), settings);
    REQUIRE(unit.size() > 500);
    for (float s : {1e-3f, 1e3f}) {
        const VoxelScene other = voxelize(scaled(s), settings);
        CAPTURE(s);
        REQUIRE(other.coords == unit.coords);
        CHECK(other.voxelSize == Approx(unit.voxelSize * s).epsilon(1e-6));
        for (size_t v = 0; v < unit.size(); ++v) REQUIRE(other.opacity[v] == Approx(unit.opacity[v]).margin(1e-4));
    }
}

TEST_CASE("No NaN in any channel for slivers tiny triangles and cancelling normals", "[voxel]") {
    Material emitter = colouredMaterial(vec3(0.8f));
    emitter.emissiveFactor = vec3(1.0f, 0.5f, 0.25f);
    emitter.emissiveStrength = 4.0f;
    Material masked = colouredMaterial(vec3(0.3f));
    masked.alphaMode = AlphaMode::Blend;
    masked.baseColorFactor.w = 0.5f;
    const vec3 a(0.11f, 0.12f, 0.13f), b(1.9f, 0.7f, 0.4f);
    std::vector<Mesh> meshes = {
        meshOf({a, b, a + 0.5f * (b - a) + vec3(0, 1e-6f, 0)}, 0, "sliver"),
        meshOf({a, a + vec3(1e-5f, 0, 0), a + vec3(0, 1e-5f, 0)}, 0, "tiny"),
        // The same triangle both ways round: the normals cancel in every voxel.
        meshOf({vec3(0, 0, 0.3f), vec3(1.3f, 0, 0.3f), vec3(0, 1.1f, 0.31f)}, 1, "front"),
        meshOf({vec3(0, 0, 0.3f), vec3(0, 1.1f, 0.31f), vec3(1.3f, 0, 0.3f)}, 1, "back"),
        meshOf({vec3(0.5f, 0.5f, 0.5f), vec3(1.5f, 0.5f, 0.5f), vec3(0.5f, 1.5f, 0.5f)}, 2, "on faces"),
    };
    const Scene scene = sceneOf(meshes, {emitter, colouredMaterial(vec3(0.2f, 0.9f, 0.4f)), masked});
    for (double h : {0.5, 0.125, 0.01}) {
        VoxelSettings settings;
        settings.voxelSize = h;
        const VoxelScene voxels = voxelize(scene, settings);
        CAPTURE(h);
        REQUIRE(voxels.size() > 0);
        REQUIRE(voxels.emission.size() == voxels.size());
        REQUIRE(allFinite(voxels));
        for (size_t v = 0; v < voxels.size(); ++v) {
            REQUIRE(voxels.opacity[v] > 0.0f);
            REQUIRE(voxels.opacity[v] <= 1.0f);
            const float length = glm::length(voxels.normal[v]);
            REQUIRE((length == 0.0f || std::fabs(length - 1.0f) < 1e-5f));
        }
    }
    // Where only the cancelling pair passes, the normal is zero and both z faces weigh equally.
    VoxelSettings settings;
    settings.voxelSize = 0.125;
    Mesh front = meshes[2], back = meshes[3];
    front.material = back.material = 0;
    const VoxelScene pair = voxelize(sceneOf({front, back}, {colouredMaterial(vec3(0.5f))}), settings);
    REQUIRE(pair.emission.empty());  // no emitters, no emission channel
    for (size_t v = 0; v < pair.size(); ++v) {
        REQUIRE(pair.normal[v] == vec3(0.0f));
        REQUIRE(pair.axisWeights[v][4] == Approx(pair.axisWeights[v][5]).epsilon(1e-6));
    }
}

TEST_CASE("The same bytes with one and two TBB threads", "[voxel]") {
    Pcg32 rng(8, 8);
    std::vector<vec3> soup;
    for (int i = 0; i < 3000; ++i) soup.push_back(vec3(rng.next1D(), rng.next1D(), rng.next1D()) * 2.0f);
    Material emitter = colouredMaterial(vec3(0.7f, 0.6f, 0.5f));
    emitter.emissiveFactor = vec3(0.5f);
    Scene scene = sceneOf({icosphere(vec3(1.0f), 0.9f, 4, 0), meshOf(soup, 1)}, {colouredMaterial(vec3(0.2f)), emitter});
    scene.meshes[0].colors.resize(scene.meshes[0].positions.size());
    for (vec4& c : scene.meshes[0].colors) c = vec4(rng.next1D(), rng.next1D(), rng.next1D(), 1.0f);
    VoxelSettings settings;
    settings.resolution = 96;
    settings.fillInterior = true;
    auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        return voxelize(scene, settings);
    };
    const VoxelScene one = run(1), two = run(2);
    REQUIRE(one.size() > 10000);
    CHECK(sameBytes(one.coords, two.coords));
    CHECK(sameBytes(one.albedo, two.albedo));
    CHECK(sameBytes(one.normal, two.normal));
    CHECK(sameBytes(one.axisWeights, two.axisWeights));
    CHECK(sameBytes(one.emission, two.emission));
    CHECK(sameBytes(one.opacity, two.opacity));
    CHECK(sameBytes(one.solid, two.solid));
}

TEST_CASE("Invalid voxel settings are refused before any work", "[voxel]") {
    const Scene scene = sceneOf({icosphere(vec3(0.0f), 1.0f, 1)});
    auto refused = [&](VoxelSettings settings, const std::string& fragment) {
        CAPTURE(fragment);
        REQUIRE_THROWS_AS(voxelize(scene, settings), SettingsError);
        REQUIRE_THROWS_WITH(voxelize(scene, settings), Catch::Contains(fragment));
    };
    VoxelSettings s;
    s.resolution = 0;
    refused(s, "resolution");
    s.resolution = -5;
    refused(s, "resolution");
    s = VoxelSettings{};
    s.voxelSize = -1.0;
    refused(s, "voxel size");
    s.voxelSize = std::nan("");
    refused(s, "voxel size");
    s.voxelSize = INFINITY;
    refused(s, "voxel size");
    s.voxelSize = 1e-7;  // 2 m across at 0.1 µm: 2·10^7 voxels along each axis
    refused(s, "voxels along axis");
    s.voxelSize = 2e-5;  // 10^5 voxels per axis fits, but the surface cuts into ~10^11 pieces
    refused(s, "pieces");
    s = VoxelSettings{};
    s.texelSamples = 0;
    refused(s, "texelSamples");

    REQUIRE_THROWS_AS(voxelize(Scene{}, VoxelSettings{}), InputError);
    Scene broken = sceneOf({meshOf({vec3(0.0f), vec3(1.0f, 0, 0), vec3(0, NAN, 0)}, -1, "bad mesh")});
    REQUIRE_THROWS_WITH(voxelize(broken, VoxelSettings{}), Catch::Contains("bad mesh") && Catch::Contains("position 2"));
}

TEST_CASE("fillInterior makes a closed cube solid through its depth", "[voxel]") {
    // A cube spanning [0.3, 4.3]³ voxels, outward faces: the surface reaches voxels 0..4 with
    // a coordinate at 0 or 4 (98 of them); the centres strictly inside are 1..4 on each axis
    // (64), of which 27 (1..3 on each axis) the surface does not reach.
    auto cube = [](float lo, float hi, bool inward) {
        const vec3 c[8] = {{lo, lo, lo}, {hi, lo, lo}, {hi, hi, lo}, {lo, hi, lo},
                           {lo, lo, hi}, {hi, lo, hi}, {hi, hi, hi}, {lo, hi, hi}};
        const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {2, 3, 7, 6}, {1, 2, 6, 5}, {0, 4, 7, 3}};
        Mesh mesh;
        mesh.name = "cube";
        mesh.material = 0;
        mesh.positions.assign(c, c + 8);
        for (const auto& f : faces) {
            const uint32_t q[4] = {uint32_t(f[0]), uint32_t(f[1]), uint32_t(f[2]), uint32_t(f[3])};
            if (inward) mesh.indices.insert(mesh.indices.end(), {q[0], q[2], q[1], q[0], q[3], q[2]});
            else mesh.indices.insert(mesh.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
        }
        return mesh;
    };
    const vec3 grey(0.4f, 0.5f, 0.6f);
    VoxelSettings settings;
    settings.voxelSize = 1.0;

    const Scene closed = sceneOf({cube(0.3f, 4.3f, false)}, {colouredMaterial(grey)});
    REQUIRE(voxelize(closed, settings).size() == 98);

    settings.fillInterior = true;
    VoxelizeStats stats;
    const VoxelScene filled = voxelize(closed, settings, nullptr, &stats);
    CHECK(stats.interiorVoxels == 27);
    REQUIRE(filled.size() == 125);
    int centresInside = 0;
    for (size_t v = 0; v < filled.size(); ++v) {
        const ivec3 c = filled.coords[v];
        const bool inside = glm::all(glm::greaterThanEqual(c, ivec3(1))) && glm::all(glm::lessThanEqual(c, ivec3(4)));
        const bool untouched = glm::all(glm::greaterThanEqual(c, ivec3(1))) && glm::all(glm::lessThanEqual(c, ivec3(3)));
        if (inside) {
            ++centresInside;
            REQUIRE(filled.solid[v] == 1);
            REQUIRE(filled.opacity[v] == 1.0f);
        }
        if (untouched) {
            REQUIRE(filled.albedo[v] == grey);
            REQUIRE(filled.normal[v] == vec3(0.0f));
        }
    }
    CHECK(centresInside == 64);

    // Not filled: a cube facing inward (a room seen from inside) and one with a face missing.
    REQUIRE(voxelize(sceneOf({cube(0.3f, 4.3f, true)}, {colouredMaterial(grey)}), settings).size() == 98);
    Mesh open = cube(0.3f, 4.3f, false);
    open.indices.resize(open.indices.size() - 6);
    VoxelizeStats openStats;
    voxelize(sceneOf({open}, {colouredMaterial(grey)}), settings, nullptr, &openStats);
    CHECK(openStats.interiorVoxels == 0);
}

TEST_CASE("The project Cornell box voxelizes with its wall colours and light", "[voxel]") {
    const Scene scene = loadGltf(test::sourceDir() + "/scenes/cornell_box.gltf");
    VoxelSettings settings;
    settings.resolution = 64;
    const VoxelScene voxels = voxelize(scene, settings);
    REQUIRE(scene.hasEmitters());
    REQUIRE(voxels.emission.size() == voxels.size());
    REQUIRE(allFinite(voxels));

    vec3 lowest(kInfinity), highest(-kInfinity), brightest(0.0f), lightEmission(0.0f);
    for (const Material& m : scene.materials) {
        lowest = glm::min(lowest, vec3(m.baseColorFactor));
        highest = glm::max(highest, vec3(m.baseColorFactor));
        if (m.emissive()) lightEmission = m.emission();
    }
    std::set<std::tuple<float, float, float>> pure;  // voxels holding one material only
    for (size_t v = 0; v < voxels.size(); ++v) {
        // Every voxel's albedo is a convex combination of the materials' colours.
        REQUIRE(glm::all(glm::greaterThanEqual(voxels.albedo[v], lowest - 1e-6f)));
        REQUIRE(glm::all(glm::lessThanEqual(voxels.albedo[v], highest + 1e-6f)));
        REQUIRE(glm::all(glm::lessThanEqual(voxels.emission[v], lightEmission * (1.0f + 1e-6f))));
        if (luminance(voxels.emission[v]) > luminance(brightest)) brightest = voxels.emission[v];
        pure.insert({voxels.albedo[v].x, voxels.albedo[v].y, voxels.albedo[v].z});
    }
    // Voxels inside the light quad (and nothing else) carry its emission exactly, and the
    // red and green walls give their colours exactly somewhere.
    CHECK(brightest == lightEmission);
    CHECK(pure.count({0.63f, 0.065f, 0.05f}) == 1);
    CHECK(pure.count({0.14f, 0.45f, 0.091f}) == 1);
}
