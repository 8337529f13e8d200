// Occlusion stepping (ERRATA eq. 17), blocking, normal-weight modes, hard cases and
// determinism (thread count, HDDA against the one-voxel DDA).
#include "lighting/lighting.h"
#include "tests/lighting/synthetic.h"

#include "core/error.h"
#include "core/rng.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>

using namespace vl;
using namespace vl::test;

namespace {

constexpr double kH = 0.25;

const NormalWeighting kModes[] = {NormalWeighting::Lambert, NormalWeighting::Villegas, NormalWeighting::SixAxis};
const VisibilityTraversal kTraversals[] = {VisibilityTraversal::Hdda, VisibilityTraversal::Dda};

bool allFinite(const VoxelScene& voxels) {
    for (size_t i = 0; i < voxels.size(); ++i) {
        const vec3 r = voxels.radiance[i];
        if (!isFinite(r) || r.x < 0.0f || r.y < 0.0f || r.z < 0.0f) return false;
        if (!isFinite(voxels.occlusion[i]) || voxels.occlusion[i] < 0.0f || voxels.occlusion[i] > 1.0f) return false;
    }
    return true;
}

// ERRATA (17) by hand: steps i = 1, 2, … of length d, w_i = min(1, 1/(i·d)).
float errataOcclusion(const std::vector<float>& alphas, float d) {
    float V = 0.0f;
    for (size_t k = 0; k < alphas.size(); ++k) {
        const float i = static_cast<float>(k + 1);
        const float w = std::min(1.0f, 1.0f / (i * d));
        V = V + w * alphas[k] * (1.0f - V);
    }
    return V;
}

}  // namespace

TEST_CASE("Occlusion along a line of partly covered voxels follows ERRATA eq 17", "[lighting]") {
    const std::vector<float> alphas{0.3f, 0.5f, 0.2f, 0.9f, 0.4f};
    // Along an axis the step length is one voxel; along a face diagonal √2.
    struct Line { ivec3 step; float d; };
    const Line lines[] = {{ivec3(1, 0, 0), 1.0f}, {ivec3(0, -1, 0), 1.0f}, {ivec3(1, 1, 0), std::sqrt(2.0f)},
                          {ivec3(0, -1, 1), std::sqrt(2.0f)}};
    for (const Line& line : lines) {
        for (VisibilityTraversal traversal : kTraversals) {
            const vec3 n = glm::normalize(vec3(line.step));
            VoxelBuilder builder(kH);
            builder.set(ivec3(0), surfaceVoxel(n));
            for (size_t k = 0; k < alphas.size(); ++k) {
                SyntheticVoxel v = surfaceVoxel(n, 0.5f, false);
                v.opacity = alphas[k];
                builder.set(line.step * static_cast<int>(k + 1), v);
            }
            VoxelScene voxels = builder.build();
            const vec3 lightPosition = vec3(line.step * 9) * static_cast<float>(kH);
            LightingSettings settings;
            settings.traversal = traversal;
            settings.normalWeights = NormalWeighting::Lambert;  // the receiver faces the light: weight 1
            lightVoxels(lightsOnly({pointLight(lightPosition, 2.0f)}), voxels, settings);
            const size_t receiver = indexOf(voxels, ivec3(0));
            const float V = errataOcclusion(alphas, line.d);
            const float r = glm::length(lightPosition);
            INFO("line " << line.step.x << "," << line.step.y << "," << line.step.z);
            CHECK(voxels.occlusion[receiver] == Approx(V).epsilon(1e-6));
            CHECK(voxels.radiance[receiver].x == Approx(0.5f * kInvPi * 2.0f / (r * r) * (1.0f - V)).epsilon(1e-5));
        }
    }
}

TEST_CASE("A solid wall one voxel thick between a light and a plane lets no light through", "[lighting]") {
    for (VisibilityTraversal traversal : kTraversals) {
        VoxelBuilder builder(kH);
        for (int u = -8; u <= 8; ++u)
            for (int v = -8; v <= 8; ++v) builder.set(ivec3(u, v, 0), surfaceVoxel(vec3(0, 0, 1)));
        for (int u = -30; u <= 30; ++u)
            for (int v = -30; v <= 30; ++v) builder.set(ivec3(u, v, 6), surfaceVoxel(vec3(0, 0, 1)));
        VoxelScene voxels = builder.build();
        LightingSettings settings;
        settings.traversal = traversal;
        const Light light = pointLight(vec3(0.1f, -0.05f, 12.0f * kH), 50.0f);
        lightVoxels(lightsOnly({light}), voxels, settings);
        size_t leaks = 0;
        for (int u = -8; u <= 8; ++u)
            for (int v = -8; v <= 8; ++v) {
                const size_t i = indexOf(voxels, ivec3(u, v, 0));
                leaks += voxels.radiance[i] == vec3(0.0f) && voxels.occlusion[i] == 1.0f ? 0 : 1;
            }
        CHECK(leaks == 0);
        CHECK(voxels.radiance[indexOf(voxels, ivec3(0, 0, 6))].x > 0.0f);  // the wall's top is lit
    }
}

TEST_CASE("A light enclosed in a solid box lights its inside and nothing outside", "[lighting]") {
    VoxelBuilder builder(kH);
    SyntheticVoxel shell;  // a thin two-sided wall: normals cancel, both faces of every axis
    shell.normal = vec3(0.0f);
    shell.axisWeights = {1, 1, 1, 1, 1, 1};
    for (int x = -3; x <= 3; ++x)
        for (int y = -3; y <= 3; ++y)
            for (int z = -3; z <= 3; ++z)
                if (std::max(std::abs(x), std::max(std::abs(y), std::abs(z))) == 3) builder.set(ivec3(x, y, z), shell);
    for (int u = -15; u <= 15; ++u)
        for (int v = -15; v <= 15; ++v) builder.set(ivec3(u, v, -6), surfaceVoxel(vec3(0, 0, 1)));
    VoxelScene voxels = builder.build();
    for (VisibilityTraversal traversal : kTraversals) {
        LightingSettings settings;
        settings.traversal = traversal;
        lightVoxels(lightsOnly({pointLight(vec3(0.05f, 0.02f, 0.07f), 1e4f)}), voxels, settings);
        size_t litOutside = 0;
        for (int u = -15; u <= 15; ++u)
            for (int v = -15; v <= 15; ++v) litOutside += voxels.radiance[indexOf(voxels, ivec3(u, v, -6))] == vec3(0.0f) ? 0 : 1;
        CHECK(litOutside == 0);
        CHECK(voxels.radiance[indexOf(voxels, ivec3(0, 0, -3))].x > 0.0f);
        CHECK(voxels.radiance[indexOf(voxels, ivec3(3, 1, 0))].x > 0.0f);
    }
}

TEST_CASE("All three normal weights agree on a flat surface", "[lighting]") {
    VoxelBuilder builder(kH);
    for (int u = -10; u <= 10; ++u)
        for (int v = -10; v <= 10; ++v) builder.set(ivec3(u, 2, v), surfaceVoxel(vec3(0, -1, 0)));
    const Scene scene = lightsOnly({pointLight(vec3(0.3f, -1.0f, 0.2f), 3.0f), directionalLight(vec3(0.2f, 1.0f, -0.5f), 1.0f)});
    std::vector<VoxelScene> results;
    for (NormalWeighting mode : kModes) {
        VoxelScene voxels = builder.build();
        LightingSettings settings;
        settings.normalWeights = mode;
        lightVoxels(scene, voxels, settings);
        results.push_back(voxels);
    }
    size_t differ = 0;
    for (size_t i = 0; i < results[0].size(); ++i)
        for (size_t m = 1; m < results.size(); ++m)
            differ += std::abs(results[m].radiance[i].x - results[0].radiance[i].x) <= 1e-6f * results[0].radiance[i].x ? 0 : 1;
    CHECK(differ == 0);
    CHECK(results[0].radiance[0].x > 0.0f);
}

TEST_CASE("A voxel on a 90 degree edge lit from either face is lit under villegas and six-axis and dark under lambert", "[lighting]") {
    // A box edge along y: top face z = 0 for x ≤ 0, side face x = 0 for z ≤ 0.
    VoxelBuilder builder(kH);
    for (int y = -3; y <= 3; ++y) {
        for (int x = -6; x < 0; ++x) builder.set(ivec3(x, y, 0), surfaceVoxel(vec3(0, 0, 1)));
        for (int z = -6; z < 0; ++z) builder.set(ivec3(0, y, z), surfaceVoxel(vec3(1, 0, 0)));
        SyntheticVoxel edge = surfaceVoxel(glm::normalize(vec3(1, 0, 1)));
        edge.axisWeights = {1, 0, 0, 0, 1, 0};  // one voxel face of each
        builder.set(ivec3(0, y, 0), edge);
    }
    // Toward the light: from the side face's side, below the top's horizon; and the reverse.
    const vec3 towardLights[] = {glm::normalize(vec3(1.0f, 0.0f, -1.5f)), glm::normalize(vec3(-1.5f, 0.0f, 1.0f))};
    for (const vec3& L : towardLights) {
        for (NormalWeighting mode : kModes) {
            VoxelScene voxels = builder.build();
            LightingSettings settings;
            settings.normalWeights = mode;
            lightVoxels(lightsOnly({directionalLight(-L, 2.0f)}), voxels, settings);
            const vec3 edge = voxels.radiance[indexOf(voxels, ivec3(0, 0, 0))];
            const float lit = std::max(L.x, 0.0f) + std::max(L.z, 0.0f);
            float expected = 0.0f;
            if (mode == NormalWeighting::Villegas) expected = 0.5f * kInvPi * 2.0f * 0.5f * lit;
            if (mode == NormalWeighting::SixAxis) expected = 0.5f * kInvPi * 2.0f * lit / 2.0f;
            INFO("mode " << toString(mode) << " L " << L.x << "," << L.z);
            CHECK(edge.x == Approx(expected).margin(1e-7));
            if (mode != NormalWeighting::Lambert) CHECK(edge.x > 0.0f);
        }
    }
}

TEST_CASE("A two-sided thin sheet is lit on the face toward the light in every mode and never NaN", "[lighting]") {
    // Normals cancel, so each face is a surface side of its own with its axis as normal, and
    // all three weights reduce to max(dir_face·L, 0) there. (Before per-face radiance,
    // lambert and villegas left such a sheet dark: its zero mean normal faced nothing.)
    VoxelBuilder builder(kH);
    SyntheticVoxel sheet;
    sheet.normal = vec3(0.0f);
    sheet.axisWeights = {0, 0, 0, 0, 1, 1};
    for (int u = -8; u <= 8; ++u)
        for (int v = -8; v <= 8; ++v) builder.set(ivec3(u, v, 0), sheet);
    for (float side : {1.0f, -1.0f}) {
        const Light light = pointLight(vec3(0.1f, 0.2f, side * 1.0f), 2.0f);
        const size_t litFace = side > 0.0f ? 4 : 5, darkFace = side > 0.0f ? 5 : 4;
        for (NormalWeighting mode : kModes) {
            VoxelScene voxels = builder.build();
            LightingSettings settings;
            settings.normalWeights = mode;
            lightVoxels(lightsOnly({light}), voxels, settings);
            CHECK(allFinite(voxels));
            size_t bad = 0;
            for (size_t i = 0; i < voxels.size(); ++i) {
                const vec3 d = light.position - voxels.centre(i);
                const float r = glm::length(d);
                // The mean normalises by the larger face of each ± pair: the sheet shows its
                // lit face's radiance I·|cosθ|/r² (not half of it).
                const float expected = 0.5f * kInvPi * 2.0f * std::abs(d.z) / r / (r * r);
                const FaceRadiance& faces = voxels.faceRadiance[i];
                bad += std::abs(voxels.radiance[i].x - expected) <= 1e-5f * expected ? 0 : 1;
                bad += std::abs(faces[litFace].x - expected) <= 1e-5f * expected ? 0 : 1;
                bad += faces[darkFace] == vec3(0.0f) && faces[0] == vec3(0.0f) && faces[2] == vec3(0.0f) ? 0 : 1;
            }
            INFO("side " << side << " mode " << toString(mode));
            CHECK(bad == 0);
        }
    }
}

TEST_CASE("Faces are grouped into the front and back of a surface and faces of their own where normals cancel", "[lighting]") {
    // A double-sided tilted surface: front n, back −n.
    const vec3 n = glm::normalize(vec3(1.0f, 2.0f, 0.0f));
    const float doubleSided[6] = {0.4f, 0.4f, 0.9f, 0.9f, 0.0f, 0.0f};
    const VoxelSides twoSides = voxelSides(n, doubleSided);
    REQUIRE(twoSides.count == 2);
    CHECK(glm::distance(twoSides.normal[0], n) < 1e-6f);
    CHECK(glm::distance(twoSides.normal[1], -n) < 1e-6f);
    const int expected[6] = {0, 1, 0, 1, -1, -1};
    for (int f = 0; f < 6; ++f) CHECK(twoSides.sideOfFace[f] == expected[f]);
    // Normals cancelled: one side per face with a surface, along the face's axis.
    const float box[6] = {1, 1, 0, 2, 0, 0};
    const VoxelSides cancelled = voxelSides(vec3(0.0f), box);
    REQUIRE(cancelled.count == 3);
    CHECK(cancelled.normal[0] == vec3(1, 0, 0));
    CHECK(cancelled.normal[1] == vec3(-1, 0, 0));
    CHECK(cancelled.normal[2] == vec3(0, -1, 0));
    CHECK(cancelled.sideOfFace[3] == 2);
    CHECK(cancelled.sideOfFace[2] == -1);
    // A face perpendicular to the mean normal shows no side of it: a side of its own.
    const float channel[6] = {0.5f, 0.5f, 1, 0, 0, 0};
    const VoxelSides floorBetweenWalls = voxelSides(vec3(0, 1, 0), channel);
    REQUIRE(floorBetweenWalls.count == 3);
    CHECK(floorBetweenWalls.normal[floorBetweenWalls.sideOfFace[0]] == vec3(1, 0, 0));
    CHECK(floorBetweenWalls.normal[floorBetweenWalls.sideOfFace[1]] == vec3(-1, 0, 0));
    CHECK(floorBetweenWalls.normal[floorBetweenWalls.sideOfFace[2]] == vec3(0, 1, 0));
    // The isotropic mean: Σ w·L / Σ_axes max(w+, w−).
    const vec3 values[6] = {vec3(1), vec3(3), vec3(2), vec3(0), vec3(7), vec3(5)};
    CHECK(faceWeightedMean(values, doubleSided)[0] == Approx((0.4f * 4.0f + 0.9f * 2.0f) / 1.3f));
}

TEST_CASE("A double-sided wall lit on one side shows its light on that side only", "[lighting]") {
    // Front normal +X, equal ± weights (how a double-sided material voxelizes); a light on
    // the −X side reaches the back faces only. The back is lit through its own side, the
    // front faces stay exactly dark in every mode, and the mean shows the lit side.
    VoxelBuilder builder(kH);
    SyntheticVoxel wall = surfaceVoxel(vec3(1, 0, 0));
    wall.axisWeights = {1, 1, 0, 0, 0, 0};
    for (int y = -6; y <= 6; ++y)
        for (int z = -6; z <= 6; ++z) builder.set(ivec3(0, y, z), wall);
    const Light light = pointLight(vec3(-1.0f, 0.1f, 0.05f), 3.0f);
    for (NormalWeighting mode : kModes) {
        VoxelScene voxels = builder.build();
        LightingSettings settings;
        settings.normalWeights = mode;
        lightVoxels(lightsOnly({light}), voxels, settings);
        size_t bad = 0;
        for (size_t i = 0; i < voxels.size(); ++i) {
            const vec3 d = light.position - voxels.centre(i);
            const float r = glm::length(d);
            const float expected = 0.5f * kInvPi * 3.0f * (-d.x / r) / (r * r);
            const FaceRadiance& faces = voxels.faceRadiance[i];
            bad += std::abs(faces[1].x - expected) <= 1e-5f * expected ? 0 : 1;
            bad += faces[0] == vec3(0.0f) ? 0 : 1;
            bad += std::abs(voxels.radiance[i].x - expected) <= 1e-5f * expected ? 0 : 1;
        }
        INFO("mode " << toString(mode));
        CHECK(bad == 0);
    }
}

TEST_CASE("Each side of a double-sided floor steps its own visibility", "[lighting]") {
    // Lights above and below a double-sided floor; a solid plate under the floor shadows the
    // light below from the back side only. The front keeps the light above, unshadowed.
    VoxelBuilder builder(kH);
    SyntheticVoxel floor = surfaceVoxel(vec3(0, 0, 1));
    floor.axisWeights = {0, 0, 0, 0, 1, 1};
    for (int x = -5; x <= 5; ++x)
        for (int y = -5; y <= 5; ++y) builder.set(ivec3(x, y, 0), floor);
    const Light above = pointLight(vec3(0.02f, 0.03f, 2.0f), 4.0f, "above");
    const Light below = pointLight(vec3(-0.03f, 0.01f, -2.0f), 4.0f, "below");
    const auto lit = [&](bool plate) {
        VoxelBuilder b = builder;
        if (plate)
            for (int x = -40; x <= 40; ++x)
                for (int y = -40; y <= 40; ++y) b.set(ivec3(x, y, -4), surfaceVoxel(vec3(0, 0, -1)));
        VoxelScene voxels = b.build();
        lightVoxels(lightsOnly({above, below}), voxels, LightingSettings{});
        return voxels;
    };
    const VoxelScene open = lit(false), shadowed = lit(true);
    const size_t centre = indexOf(open, ivec3(0));
    const auto irradiance = [&](const Light& light) {
        const vec3 d = light.position - open.centre(centre);
        const float r = glm::length(d);
        return 0.5f * kInvPi * 4.0f * std::abs(d.z) / r / (r * r);
    };
    CHECK(open.faceRadiance[centre][4].x == Approx(irradiance(above)).epsilon(1e-5));
    CHECK(open.faceRadiance[centre][5].x == Approx(irradiance(below)).epsilon(1e-5));
    const size_t shadowedCentre = indexOf(shadowed, ivec3(0));
    CHECK(shadowed.faceRadiance[shadowedCentre][4].x == Approx(irradiance(above)).epsilon(1e-5));
    CHECK(shadowed.faceRadiance[shadowedCentre][5] == vec3(0.0f));
    // Two lights, each reaching one side: one unshadowed (V 0), one shadowed (V 1).
    CHECK(shadowed.occlusion[shadowedCentre] == Approx(0.5f));
}

namespace {

// A plane, a box on it and a thin partly covered wall: the scene of the hard cases.
VoxelScene cluttered() {
    VoxelBuilder builder(kH);
    for (int u = -12; u <= 12; ++u)
        for (int v = -12; v <= 12; ++v) builder.set(ivec3(u, v, 0), surfaceVoxel(vec3(0, 0, 1)));
    for (int x = 3; x <= 6; ++x)
        for (int y = -2; y <= 2; ++y)
            for (int z = 1; z <= 4; ++z) builder.set(ivec3(x, y, z), surfaceVoxel(glm::normalize(vec3(1, 1, 1))));
    for (int y = -6; y <= 6; ++y)
        for (int z = 1; z <= 5; ++z) {
            SyntheticVoxel v = surfaceVoxel(vec3(-1, 0, 0), 0.8f, false);
            v.opacity = 0.4f;
            builder.set(ivec3(-5, y, z), v);
        }
    return builder.build();
}

}  // namespace

TEST_CASE("Hard cases stay finite: lights inside voxels and on corners and outside the grid and extreme intensities and 64 lights and grazing", "[lighting]") {
    const float h = static_cast<float>(kH);
    std::vector<Light> placements = {
        pointLight(vec3(0.0f), 1.0f, "at a voxel centre"),
        pointLight(vec3(0.2f, 0.1f, 0.3f) * h, 1.0f, "inside a voxel"),
        pointLight(vec3(0.5f, 0.5f, 0.5f) * h, 1.0f, "on a voxel corner"),
        pointLight(vec3(4.5f, 0.5f, 2.5f) * h, 1.0f, "on a corner inside the box"),
        pointLight(vec3(200.0f, -150.0f, 90.0f), 1.0f, "far outside the grid"),
        pointLight(vec3(-40.0f, 3.0f, -2.0f) * h, 1.0f, "below and outside"),
        directionalLight(vec3(0.0f, 0.0f, -1.0f), 1.0f),
        directionalLight(vec3(1.0f, 0.0f, 0.0f), 1.0f),  // grazing the plane
    };
    for (NormalWeighting mode : kModes) {
        for (const Light& light : placements) {
            VoxelScene voxels = cluttered();
            LightingSettings settings;
            settings.normalWeights = mode;
            lightVoxels(lightsOnly({light}), voxels, settings);
            INFO(light.name << " " << toString(mode));
            CHECK(allFinite(voxels));
        }
    }

    // A light in the plane (N·L = 0 on every plane voxel) gives the plane exactly nothing.
    {
        VoxelScene voxels = cluttered();
        lightVoxels(lightsOnly({pointLight(vec3(-30.0f, 1.0f, 0.0f) * h, 5.0f)}), voxels, LightingSettings{});
        size_t lit = 0;
        for (int u = -12; u <= 12; ++u)
            for (int v = -12; v <= 12; ++v) lit += voxels.radiance[indexOf(voxels, ivec3(u, v, 0))] == vec3(0.0f) ? 0 : 1;
        CHECK(allFinite(voxels));
        CHECK(lit == 0);
    }

    // Radiance is linear in intensity from 1e-6 to 1e9 (visibility does not depend on it).
    {
        VoxelScene dim = cluttered(), bright = cluttered();
        const vec3 position = vec3(-1.0f, 2.0f, 7.0f) * h;
        lightVoxels(lightsOnly({pointLight(position, 1e-6f)}), dim, LightingSettings{});
        lightVoxels(lightsOnly({pointLight(position, 1e9f)}), bright, LightingSettings{});
        CHECK(allFinite(dim));
        CHECK(allFinite(bright));
        size_t bad = 0, lit = 0;
        for (size_t i = 0; i < dim.size(); ++i) {
            const float a = dim.radiance[i].x / 1e-6f, b = bright.radiance[i].x / 1e9f;
            bad += std::abs(a - b) <= 1e-5f * std::max(a, b) ? 0 : 1;
            lit += a > 0.0f ? 1 : 0;
        }
        CHECK(bad == 0);
        CHECK(lit > 100);
    }

    // 64 lights: the sum of the 64 single-light results.
    {
        std::vector<Light> lights;
        Pcg32 rng(7, 3);
        for (int k = 0; k < 64; ++k)
            lights.push_back(pointLight(vec3(rng.next1D() * 30.0f - 15.0f, rng.next1D() * 30.0f - 15.0f, rng.next1D() * 12.0f - 2.0f) * h,
                                        0.5f + rng.next1D(), "light " + std::to_string(k)));
        VoxelScene all = cluttered();
        lightVoxels(lightsOnly(lights), all, LightingSettings{});
        CHECK(allFinite(all));
        std::vector<vec3> sum(all.size(), vec3(0.0f));
        for (const Light& light : lights) {
            VoxelScene one = cluttered();
            lightVoxels(lightsOnly({light}), one, LightingSettings{});
            for (size_t i = 0; i < one.size(); ++i) sum[i] += one.radiance[i];
        }
        size_t bad = 0;
        for (size_t i = 0; i < all.size(); ++i) bad += std::abs(all.radiance[i].x - sum[i].x) <= 1e-4f * sum[i].x + 1e-12f ? 0 : 1;
        CHECK(bad == 0);
    }
}

namespace {

// A seeded random scene in two clusters 300 voxels apart (empty NanoVDB nodes between them),
// with partial and solid voxels, every light type and an emissive triangle.
struct RandomScene {
    VoxelScene voxels;
    Scene scene;
};

RandomScene randomScene() {
    RandomScene result;
    VoxelBuilder builder(kH);
    Pcg32 rng(2024, 11);
    for (int cluster = 0; cluster < 2; ++cluster) {
        const ivec3 offset(cluster * 300, cluster * 17, -cluster * 40);
        for (int x = 0; x < 20; ++x)
            for (int y = 0; y < 20; ++y)
                for (int z = 0; z < 20; ++z) {
                    if (rng.next1D() > 0.12f) continue;
                    SyntheticVoxel v;
                    v.albedo = vec3(rng.next1D(), rng.next1D(), rng.next1D());
                    const vec3 n(rng.next1D() - 0.5f, rng.next1D() - 0.5f, rng.next1D() - 0.5f);
                    v.normal = rng.next1D() < 0.1f ? vec3(0.0f) : glm::normalize(n);
                    for (float& w : v.axisWeights) w = rng.next1D() < 0.5f ? 0.0f : rng.next1D();
                    v.opacity = 0.05f + 0.95f * rng.next1D();
                    v.solid = rng.next1D() < 0.3f;
                    builder.set(offset + ivec3(x, y, z), v);
                }
    }
    result.voxels = builder.build();
    const float h = static_cast<float>(kH);
    Light spot = pointLight(vec3(10.0f, 10.0f, 30.0f) * h, 20.0f, "spot");
    spot.type = LightType::Spot;
    spot.direction = glm::normalize(vec3(0.1f, 0.0f, -1.0f));
    spot.outerConeAngle = 0.7f;
    result.scene = lightsOnly({pointLight(vec3(5.5f, 10.5f, 9.5f) * h, 10.0f, "corner"),
                               pointLight(vec3(150.0f, 12.0f, -10.0f) * h, 10.0f, "between clusters"),
                               directionalLight(vec3(-0.3f, 0.2f, -1.0f), 1.0f), spot});
    Material material;
    material.emissiveFactor = vec3(1.0f, 0.8f, 0.6f);
    material.emissiveStrength = 3.0f;
    result.scene.materials.push_back(material);
    Mesh mesh;
    mesh.name = "emitter/0";
    mesh.material = 0;
    mesh.positions = {vec3(4.0f, 4.0f, 22.0f) * h, vec3(14.0f, 6.0f, 22.0f) * h, vec3(8.0f, 15.0f, 21.0f) * h};
    mesh.indices = {0, 2, 1};
    result.scene.meshes.push_back(mesh);
    return result;
}

}  // namespace

TEST_CASE("Radiance and occlusion are the same bytes with 1 and 2 threads", "[lighting]") {
    const RandomScene base = randomScene();
    VoxelScene one = base.voxels, two = base.voxels;
    LightingSettings settings;
    settings.threads = 1;
    lightVoxels(base.scene, one, settings);
    settings.threads = 2;
    lightVoxels(base.scene, two, settings);
    REQUIRE(one.size() == two.size());
    CHECK(std::memcmp(one.radiance.data(), two.radiance.data(), one.size() * sizeof(vec3)) == 0);
    CHECK(std::memcmp(one.faceRadiance.data(), two.faceRadiance.data(), one.size() * sizeof(FaceRadiance)) == 0);
    CHECK(std::memcmp(one.occlusion.data(), two.occlusion.data(), one.size() * sizeof(float)) == 0);
    CHECK(allFinite(one));
}

TEST_CASE("HDDA empty-space skipping gives the same bytes as the one-voxel DDA in fewer steps", "[lighting]") {
    const RandomScene base = randomScene();
    for (NormalWeighting mode : kModes) {
        VoxelScene hdda = base.voxels, dda = base.voxels;
        LightingSettings settings;
        settings.normalWeights = mode;
        const LightingStats hddaStats = lightVoxels(base.scene, hdda, settings);
        settings.traversal = VisibilityTraversal::Dda;
        const LightingStats ddaStats = lightVoxels(base.scene, dda, settings);
        INFO("mode " << toString(mode));
        CHECK(std::memcmp(hdda.radiance.data(), dda.radiance.data(), hdda.size() * sizeof(vec3)) == 0);
        CHECK(std::memcmp(hdda.faceRadiance.data(), dda.faceRadiance.data(), hdda.size() * sizeof(FaceRadiance)) == 0);
        CHECK(std::memcmp(hdda.occlusion.data(), dda.occlusion.data(), hdda.size() * sizeof(float)) == 0);
        CHECK(hddaStats.voxelLightEvaluations == ddaStats.voxelLightEvaluations);
        CHECK(hddaStats.visibilitySteps < ddaStats.visibilitySteps);
    }
}

TEST_CASE("Lighting settings and lights out of range are rejected with the setting or light named", "[lighting]") {
    VoxelBuilder builder(kH);
    builder.set(ivec3(0), surfaceVoxel(vec3(0, 0, 1)));
    VoxelScene voxels = builder.build();
    const Scene scene = lightsOnly({pointLight(vec3(0, 0, 1), 1.0f, "lamp")});
    LightingSettings strata;
    strata.emitterStrata = 0;
    CHECK_THROWS_AS(lightVoxels(scene, voxels, strata), SettingsError);
    LightingSettings zero;
    zero.attenuation = AttenuationCoefficients{0.0f, 0.0f, 0.0f};
    CHECK_THROWS_WITH(lightVoxels(scene, voxels, zero), Catch::Contains("not all zero"));
    LightingSettings unknown;
    unknown.lightAttenuation["desk lamp"] = AttenuationCoefficients{};
    CHECK_THROWS_WITH(lightVoxels(scene, voxels, unknown), Catch::Contains("'desk lamp'"));
    const Scene bad = lightsOnly({pointLight(vec3(0, 0, 1), std::nanf(""), "lamp")});
    CHECK_THROWS_WITH(lightVoxels(bad, voxels, LightingSettings{}), Catch::Contains("'lamp'"));
    CHECK_THROWS_AS(parseNormalWeighting("phong"), SettingsError);
    voxels.opacity.pop_back();
    CHECK_THROWS_WITH(lightVoxels(scene, voxels, LightingSettings{}), Catch::Contains("opacity"));
}

TEST_CASE("A low light behind a wall standing on a floor does not leak under the wall", "[lighting]") {
    // The ray of a floor voxel starts on its top face, in the layer above the floor, so it
    // meets the wall's second row instead of slipping through the floor's own layer.
    VoxelBuilder builder(kH);
    for (int x = -20; x <= 20; ++x)
        for (int y = -10; y <= 10; ++y) builder.set(ivec3(x, y, 0), surfaceVoxel(vec3(0, 0, 1)));
    for (int y = -30; y <= 30; ++y)
        for (int z = 0; z <= 10; ++z) builder.set(ivec3(0, y, z), surfaceVoxel(vec3(1, 0, 0)));
    for (VisibilityTraversal traversal : kTraversals) {
        VoxelScene voxels = builder.build();
        LightingSettings settings;
        settings.traversal = traversal;
        const Light light = pointLight(vec3(30.0f, 0.5f, 1.0f) * static_cast<float>(kH), 100.0f);
        lightVoxels(lightsOnly({light}), voxels, settings);
        size_t leaks = 0, litInFront = 0;
        for (int x = -20; x <= 20; ++x)
            for (int y = -10; y <= 10; ++y) {
                const vec3 r = voxels.radiance[indexOf(voxels, ivec3(x, y, 0))];
                if (x < 0) leaks += r == vec3(0.0f) ? 0 : 1;
                if (x > 0) litInFront += r.x > 0.0f ? 1 : 0;
            }
        CHECK(leaks == 0);
        CHECK(litInFront == 20u * 21u);
    }
}

TEST_CASE("A 45 degree plane does not shadow itself under a grazing light", "[lighting]") {
    // The plane x = z + 0.3 crosses two voxels per step of its staircase; all are solid.
    const vec3 n = glm::normalize(vec3(-1.0f, 0.0f, 1.0f));
    const vec3 tangent = glm::normalize(vec3(1.0f, 0.0f, 1.0f));
    VoxelBuilder builder(kH);
    for (int a = -15; a <= 15; ++a)
        for (int y = -5; y <= 5; ++y)
            for (int b = a - 1; b <= a; ++b) builder.set(ivec3(a, y, b), surfaceVoxel(n));
    const float elevations[] = {0.1f, 0.3f, 0.8f};  // radians above the plane
    for (float elevation : elevations) {
        const vec3 L = glm::normalize(std::cos(elevation) * glm::normalize(tangent + vec3(0.0f, 0.2f, 0.0f)) +
                                      std::sin(elevation) * n);
        for (VisibilityTraversal traversal : kTraversals) {
            VoxelScene voxels = builder.build();
            LightingSettings settings;
            settings.traversal = traversal;
            settings.normalWeights = NormalWeighting::Lambert;
            lightVoxels(lightsOnly({directionalLight(-L, 2.0f)}), voxels, settings);
            const float expected = 0.5f * kInvPi * 2.0f * glm::dot(n, L);
            size_t bad = 0;
            for (size_t i = 0; i < voxels.size(); ++i)
                bad += std::abs(voxels.radiance[i].x - expected) <= 1e-5f * expected && voxels.occlusion[i] == 0.0f ? 0 : 1;
            INFO("elevation " << elevation);
            CHECK(bad == 0);
        }
    }
}

TEST_CASE("A ray through exact voxel corners leaves an empty node where the one-voxel DDA does", "[lighting]") {
    // From (−1, −1, 0) along the xy diagonal the ray crosses x and y at the same instants; the
    // DDA crosses x first (lowest axis on ties), so after the empty leaf [0, 7]³ it visits
    // (8, 7, 0) and never (7, 8, 0). A leap that rounds the exit point would land on (8, 8, 0).
    const vec3 n = glm::normalize(vec3(1.0f, 1.0f, 0.0f));
    const ivec3 blockers[] = {ivec3(8, 7, 0), ivec3(7, 8, 0)};
    for (const ivec3& blocker : blockers) {
        VoxelBuilder builder(kH);
        builder.set(ivec3(-1, -1, 0), surfaceVoxel(n));
        builder.set(blocker, surfaceVoxel(n));
        for (VisibilityTraversal traversal : kTraversals) {
            VoxelScene voxels = builder.build();
            LightingSettings settings;
            settings.traversal = traversal;
            lightVoxels(lightsOnly({pointLight(vec3(24.0f, 24.0f, 0.0f) * static_cast<float>(kH), 1.0f)}), voxels, settings);
            const float V = voxels.occlusion[indexOf(voxels, ivec3(-1, -1, 0))];
            INFO("blocker " << blocker.x << "," << blocker.y << " hdda " << (traversal == VisibilityTraversal::Hdda));
            CHECK(V == (blocker.x == 8 ? 1.0f : 0.0f));
        }
    }
}
