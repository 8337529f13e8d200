// Bright patches (bake/bright_patches.h): which faces become patches and what they carry, and
// the irradiance a patch gives a gather point against the closed form.
#include "bake/bright_patches.h"

#include "scene/scene.h"
#include "trace/bvh.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;

namespace {

constexpr double kH = 0.1;

// A floor of 20 × 20 voxels (layer y = 0, facing +Y, radiance 1) with a 3 × 3 block of
// radiance `bright` at x, z ∈ 4 … 6.
VoxelScene litFloor(float bright) {
    VoxelScene voxels;
    voxels.voxelSize = kH;
    for (int x = 0; x < 20; ++x)
        for (int z = 0; z < 20; ++z) {
            voxels.coords.push_back(ivec3(x, 0, z));
            voxels.albedo.push_back(vec3(0.5f));
            voxels.normal.push_back(vec3(0, 1, 0));
            voxels.axisWeights.push_back(AxisWeights{0, 0, 1, 0, 0, 0});
            voxels.opacity.push_back(1.0f);
            voxels.solid.push_back(1);
            voxels.surfaceOffset.push_back(vec3(0.0f, 0.25f, 0.0f));
            const bool inBlock = x >= 4 && x <= 6 && z >= 4 && z <= 6;
            FaceRadiance faces{};
            faces[2] = vec3(inBlock ? bright : 1.0f);
            voxels.faceRadiance.push_back(faces);
            voxels.radiance.push_back(faceWeightedMean(faces.data(), voxels.axisWeights.back().data()));
        }
    return voxels;
}

}  // namespace

TEST_CASE("Bright faces become patches that carry exactly their power, and leave the rest", "[bake]") {
    // Mean face radiance (391 + 9·50) / 400 = 2.1025; with factor 2 only the block is bright.
    // Cells of 4 voxels split it into x, z ∈ {4, 5, 6} → cells 1 (4 … 7): one patch.
    const VoxelScene voxels = litFloor(50.0f);
    BrightPatchSettings settings;
    settings.factor = 2.0f;
    settings.cellVoxels = 4;
    const BrightPatchSplit split = splitBrightPatches(voxels, settings);
    REQUIRE(split.patches.size() == 1);
    CHECK(split.faces == 9);
    const BrightPatch& patch = split.patches[0];
    CHECK(patch.area == Approx(9 * kH * kH));
    CHECK(patch.radiance.x == Approx(50.0f));
    CHECK(patch.normal == vec3(0, 1, 0));
    // The power-weighted surface point: the block's centre, on the surface (0.25 voxel up).
    CHECK(patch.position.x == Approx(5 * kH));
    CHECK(patch.position.y == Approx(0.25 * kH));
    CHECK(patch.position.z == Approx(5 * kH));
    for (size_t i = 0; i < voxels.size(); ++i) {
        const ivec3 c = voxels.coords[i];
        const bool inBlock = c.x >= 4 && c.x <= 6 && c.z >= 4 && c.z <= 6;
        CHECK(split.restFaces[i][2].x == (inBlock ? 0.0f : 1.0f));
        CHECK(split.restRadiance[i] == faceWeightedMean(split.restFaces[i].data(), voxels.axisWeights[i].data()));
    }

    // Cells of 2 split the block into 4 patches (x and z: 4 … 5 and 6 … 7) of 4, 2, 2 and 1
    // faces; the most powerful two when only two may be taken.
    settings.cellVoxels = 2;
    CHECK(splitBrightPatches(voxels, settings).patches.size() == 4);
    settings.maxPatches = 2;
    const BrightPatchSplit two = splitBrightPatches(voxels, settings);
    REQUIRE(two.patches.size() == 2);
    CHECK(two.faces == 6);
    CHECK(two.patches[0].area + two.patches[1].area == Approx(6 * kH * kH));

    // Nothing is bright in a uniform floor, and factor 0 turns the split off.
    CHECK(splitBrightPatches(litFloor(1.0f), BrightPatchSettings{}).patches.empty());
    settings.factor = 0.0f;
    CHECK(splitBrightPatches(voxels, settings).patches.empty());
}

TEST_CASE("A bright slanted surface's patch carries its true area along its own normal", "[bake]") {
    // Voxels of a plane with normal n = (3, 4, 0)/5, each holding area a of it: its axis
    // weights are the area's projections, a·0.6 on +X and a·0.8 on +Y (voxelize.cpp). A patch
    // must send L·a per voxel along n, not L·(0.6 + 0.8)·a split over the axes: summing the
    // faces over-counts a slanted surface by ‖n‖₁, and patches square to the axes light
    // receivers the surface faces away from (a turned Cornell box: 4–8% too much indirect).
    const vec3 n(0.6f, 0.8f, 0.0f);
    const float a = 0.7f * float(kH * kH);
    VoxelScene voxels;
    voxels.voxelSize = kH;
    for (int k = 0; k < 12; ++k)
        for (int z = 0; z < 12; ++z) {
            voxels.coords.push_back(ivec3(k, 3 - k, z));  // a staircase along the plane
            voxels.albedo.push_back(vec3(0.5f));
            voxels.normal.push_back(n);
            voxels.axisWeights.push_back(AxisWeights{a * n.x / float(kH * kH), 0, a * n.y / float(kH * kH), 0, 0, 0});
            voxels.opacity.push_back(1.0f);
            voxels.solid.push_back(1);
            voxels.surfaceOffset.push_back(vec3(0.0f));
            const bool bright = k < 4 && z < 4;
            FaceRadiance faces{};
            faces[0] = faces[2] = vec3(bright ? 40.0f : 1.0f);
            voxels.faceRadiance.push_back(faces);
            voxels.radiance.push_back(faceWeightedMean(faces.data(), voxels.axisWeights.back().data()));
        }
    BrightPatchSettings settings;
    settings.factor = 4.0f;
    settings.cellVoxels = 4;
    const BrightPatchSplit split = splitBrightPatches(voxels, settings);
    REQUIRE(split.patches.size() == 1);
    CHECK(split.faces == 2 * 16);
    const BrightPatch& patch = split.patches[0];
    CHECK(patch.area == Approx(16 * a));
    CHECK(patch.radiance.x == Approx(40.0f));
    CHECK(patch.normal.x == Approx(n.x));
    CHECK(patch.normal.y == Approx(n.y));
    CHECK(patch.normal.z == Approx(0.0f).margin(1e-6));
}

TEST_CASE("A bright patch gives a gather point L A cos cos / r^2 far off, pi L close, nothing behind a wall", "[bake]") {
    BrightPatch patch;
    patch.position = vec3(0.0f, 2.0f, 0.0f);
    patch.normal = vec3(0.0f, -1.0f, 0.0f);  // facing down at the point
    patch.area = 0.01f;
    patch.radiance = vec3(30.0f, 20.0f, 10.0f);
    GatherPoint point;
    point.position = vec3(0.3f, 0.0f, -0.4f);
    point.normal = vec3(0.0f, 1.0f, 0.0f);
    const float lift = 0.05f, h = 0.02f;

    const auto irradianceWith = [&](const Scene& scene) {
        const SceneTriangles triangles = gatherTriangles(scene);
        const Bvh bvh = Bvh::build(triangles);
        std::vector<vec3> irradiance(1, vec3(1.0f));
        addBrightPatchIrradiance({point}, {point.position + point.normal * lift}, {patch}, bvh.view(), h, irradiance);
        return irradiance[0] - vec3(1.0f);
    };
    // A small triangle far off the path, so the BVH is not empty.
    Scene open;
    Mesh aside;
    aside.name = "aside";
    aside.positions = {vec3(5, 0, 5), vec3(6, 0, 5), vec3(5, 0, 6)};
    aside.indices = {0, 1, 2};
    open.meshes.push_back(aside);
    open.materials.push_back(Material{});
    const vec3 d = patch.position - (point.position + point.normal * lift);
    const float r = glm::length(d), cosine = d.y / r;
    const vec3 expected = patch.radiance * (patch.area * cosine * cosine / (r * r));
    // A 10 cm square 2 m off: the point-source form within (side / r)² ≈ 0.25%.
    const vec3 got = irradianceWith(open);
    for (int c = 0; c < 3; ++c) CHECK(got[c] == Approx(expected[c]).epsilon(3e-3));

    // Right under the middle of a 1 m² patch, 1 mm below: the patch fills nearly the whole
    // hemisphere, E → π L (the point-source form would give L·A/r², a million times more).
    {
        const BrightPatch saved = patch;
        const GatherPoint savedPoint = point;
        patch.area = 1.0f;
        patch.position = vec3(0.0f, lift + 0.001f, 0.0f);
        point.position = vec3(0.0f);
        const vec3 close = irradianceWith(open);
        for (int c = 0; c < 3; ++c) CHECK(close[c] == Approx(kPi * patch.radiance[c]).epsilon(0.01));
        patch = saved;
        point = savedPoint;
    }

    // A board half way up blocks it.
    Scene blocked = open;
    Mesh board;
    board.name = "board";
    board.positions = {vec3(-1, 1, -1), vec3(1, 1, -1), vec3(1, 1, 1), vec3(-1, 1, 1)};
    board.indices = {0, 2, 1, 0, 3, 2};
    blocked.meshes.push_back(board);
    CHECK(irradianceWith(blocked) == vec3(0.0f));

    // A patch facing away, or behind the point's surface, gives nothing.
    patch.normal = vec3(0.0f, 1.0f, 0.0f);
    CHECK(irradianceWith(open) == vec3(0.0f));
    patch.normal = vec3(0.0f, 1.0f, 0.0f);
    patch.position = vec3(0.0f, -2.0f, 0.0f);
    CHECK(irradianceWith(open) == vec3(0.0f));

    // One origin for every point, or an error that says how many came.
    const SceneTriangles triangles = gatherTriangles(open);
    const Bvh bvh = Bvh::build(triangles);
    std::vector<vec3> irradiance(2, vec3(0.0f));
    CHECK_THROWS_WITH(addBrightPatchIrradiance({point, point}, {point.position}, {patch}, bvh.view(), h, irradiance),
                      Catch::Contains("1 origins and 2 irradiance values for 2 gather points"));
}
