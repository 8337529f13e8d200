// Bright patches (gather/bright_patches.h): which voxel sides become patches and what they carry,
// and the irradiance their sampled surface points give a gather point against closed forms.
#include "gather/bright_patches.h"

#include "lighting/surface_points.h"
#include "support/room_scenes.h"
#include "support/form_factor.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"
#include "voxel/voxelize.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;
using namespace vl::test;

namespace {

constexpr double kH = 0.05;

// A scene voxelized at kH with its traced triangles and surface points; every face starts at
// radiance 1, and `lit` picks the voxels whose faces `bright` gives instead.
struct Voxelized {
    Scene scene;
    VoxelScene voxels;
    SceneTriangles triangles;
    Bvh bvh;
    TraceScene traced;
    VoxelSurfacePoints points;
};

template <typename Lit>
Voxelized voxelizedWithLight(Scene scene, float bright, Lit&& lit) {
    Voxelized v;
    v.scene = std::move(scene);
    VoxelSettings settings;
    settings.voxelSize = kH;
    v.voxels = voxelize(v.scene, settings);
    v.triangles = gatherTriangles(v.scene);
    v.bvh = Bvh::build(v.triangles);
    v.traced = TraceScene::build(v.scene, v.triangles);
    v.points = voxelSurfacePoints(v.voxels, v.traced.view(), 4);
    v.voxels.faceRadiance.assign(v.voxels.size(), FaceRadiance{});
    v.voxels.radiance.assign(v.voxels.size(), vec3(0.0f));
    for (size_t i = 0; i < v.voxels.size(); ++i) {
        for (int f = 0; f < 6; ++f)
            if (v.voxels.axisWeights[i][size_t(f)] > 0.0f)
                v.voxels.faceRadiance[i][size_t(f)] = vec3(lit(v.voxels.centre(i), f) ? bright : 1.0f);
        v.voxels.radiance[i] = faceWeightedMean(v.voxels.faceRadiance[i].data(), v.voxels.axisWeights[i].data());
    }
    return v;
}

// A 2 × 2 m floor (y = 0, facing +Y) with the 5 × 5 voxels around its middle (a 0.25 m square,
// voxel centres at multiples of kH) lit `bright`.
Voxelized litFloor(float bright) {
    Scene scene;
    const int grey = addLambert(scene, vec3(0.5f));
    addQuad(scene, "floor", grey, vec3(-1, 0, -1), vec3(-1, 0, 1), vec3(1, 0, 1), vec3(1, 0, -1));
    return voxelizedWithLight(std::move(scene), bright, [](const vec3& c, int f) {
        return f == 2 && std::abs(c.x) < 0.15f && std::abs(c.z) < 0.15f;
    });
}

}  // namespace

TEST_CASE("Bright voxel sides become patches that carry their surface's area and leave the rest", "[bake]") {
    const Voxelized v = litFloor(50.0f);
    BrightPatchSettings settings;
    settings.factor = 2.0f;
    settings.cellVoxels = 4;  // 20 cm cells: the 30 cm square spans a few
    const BrightPatchSplit split = splitBrightPatches(v.voxels, v.points, settings);
    REQUIRE(!split.patches.empty());
    // Every bright voxel's face leaves the rest, every other stays.
    size_t brightFaces = 0;
    double brightArea = 0.0;
    for (size_t i = 0; i < v.voxels.size(); ++i) {
        const bool bright = v.voxels.faceRadiance[i][2].x > 1.0f;
        brightFaces += bright;
        CHECK(split.restFaces[i][2].x == (bright ? 0.0f : v.voxels.faceRadiance[i][2].x));
        if (bright)
            for (uint32_t k = v.points.begin[i * 6]; k < v.points.begin[i * 6 + 1]; ++k) brightArea += v.points.points[k].area;
    }
    CHECK(split.faces == brightFaces);
    // The patches' points are the bright sides' surface points: their area, their radiance,
    // facing up, on the floor.
    double area = 0.0;
    for (const BrightPatch& patch : split.patches) area += patch.area;
    CHECK(area == Approx(brightArea).epsilon(1e-5));
    for (const BrightPoint& p : split.points) {
        CHECK(p.radiance.x == 50.0f);
        CHECK(p.geometricNormal.y == Approx(1.0f));
        CHECK(p.position.y == Approx(0.0f).margin(1e-6));
    }
    // Each patch's points' draw table ends at 1.
    for (const BrightPatch& patch : split.patches) CHECK(split.pointCdf[patch.firstPoint + patch.pointCount - 1] == 1.0f);

    // The most powerful patches when fewer may be taken; nothing bright in a uniform floor; and
    // factor 0 turns the split off.
    settings.maxPatches = 1;
    const BrightPatchSplit one = splitBrightPatches(v.voxels, v.points, settings);
    REQUIRE(one.patches.size() == 1);
    for (const BrightPatch& patch : split.patches) CHECK(one.patches[0].area >= patch.area * 0.999f);
    const Voxelized uniform = litFloor(1.0f);
    CHECK(splitBrightPatches(uniform.voxels, uniform.points, BrightPatchSettings{}).patches.empty());
    settings.factor = 0.0f;
    CHECK(splitBrightPatches(v.voxels, v.points, settings).patches.empty());
}

TEST_CASE("Sampled bright patches give a point the form factor's light, pi L close, nothing behind a wall or a panel",
          "[bake]") {
    // The 0.25 m bright square seen from above: the estimate against the closed form of the
    // square (support/form_factor.h).
    const float L = 50.0f;
    const Voxelized v = litFloor(L);
    BrightPatchSettings settings;
    settings.factor = 2.0f;
    const BrightPatchSplit split = splitBrightPatches(v.voxels, v.points, settings);
    double area = 0.0;
    for (const BrightPatch& patch : split.patches) area += patch.area;
    REQUIRE(area == Approx(0.0625).epsilon(1e-4));
    const vec3 above(0.2f, 1.0f, 0.1f), down(0.0f, -1.0f, 0.0f);
    const auto exact = [&](const vec3& p) {
        return kPi * L * rectangleFormFactor(-0.125 - p.x, 0.125 - p.x, -0.125 - p.z, 0.125 - p.z, p.y);
    };
    CHECK(brightPatchIrradiance(split, v.bvh.view(), above, down, 256, 7).x == Approx(exact(above)).epsilon(0.03));
    // Close (5 cm over its middle, four spacings of its points) the estimate stays within 15% of
    // the closed form, where the whole patch as a point, L·A·cos·cos/r², would give 9 times it.
    const vec3 close(0.0f, 0.05f, 0.0f);
    CHECK(brightPatchIrradiance(split, v.bvh.view(), close, down, 256, 7).x == Approx(exact(close)).epsilon(0.15));
    // Right against it (1 mm) the estimate stays bounded by π L.
    CHECK(brightPatchIrradiance(split, v.bvh.view(), vec3(0.0f, 0.001f, 0.0f), down, 256, 7).x <= kPi * L);

    // Facing away from it, or under the floor: nothing.
    CHECK(brightPatchIrradiance(split, v.bvh.view(), above, vec3(0, 1, 0), 256, 7) == vec3(0.0f));
    CHECK(brightPatchIrradiance(split, v.bvh.view(), vec3(0.0f, -0.5f, 0.0f), vec3(0, 1, 0), 256, 7) == vec3(0.0f));

    // A board half way up hides it.
    Scene boarded = v.scene;
    addQuad(boarded, "board", 0, vec3(-1, 0.5f, -1), vec3(1, 0.5f, -1), vec3(1, 0.5f, 1), vec3(-1, 0.5f, 1));
    const SceneTriangles triangles = gatherTriangles(boarded);
    const Bvh bvh = Bvh::build(triangles);
    CHECK(brightPatchIrradiance(split, bvh.view(), above, down, 256, 7) == vec3(0.0f));
}

TEST_CASE("A thin double-sided panel lit on one side sends nothing to a point on its other side", "[bake]") {
    // A double-sided panel in the plane x = 0.02 (inside one voxel layer), its −X side lit: a
    // gather point on its +X side, where the voxels put both sides in one place, must not take
    // the lit side's light (the squares of whole patches gave such points 70 times the light
    // their rays read on the grey-white room's window frames).
    Scene scene;
    const int grey = addLambert(scene, vec3(0.5f));
    scene.materials[size_t(grey)].doubleSided = true;
    addQuad(scene, "panel", grey, vec3(0.02f, 0, -0.5f), vec3(0.02f, 1, -0.5f), vec3(0.02f, 1, 0.5f), vec3(0.02f, 0, 0.5f));
    const Voxelized v = voxelizedWithLight(std::move(scene), 40.0f, [](const vec3&, int f) { return f == 1; });  // −X faces
    BrightPatchSettings settings;
    settings.factor = 1.5f;  // the mean face is 20.5
    const BrightPatchSplit split = splitBrightPatches(v.voxels, v.points, settings);
    REQUIRE(!split.patches.empty());
    for (const BrightPoint& p : split.points) CHECK(p.geometricNormal.x == Approx(-1.0f));
    // On the +X side, a hair off the panel, facing +X: nothing; on the −X side, facing −X: light.
    CHECK(brightPatchIrradiance(split, v.bvh.view(), vec3(0.0201f, 0.5f, 0.0f), vec3(1, 0, 0), 256, 3) == vec3(0.0f));
    CHECK(brightPatchIrradiance(split, v.bvh.view(), vec3(-0.3f, 0.5f, 0.0f), vec3(-1, 0, 0), 256, 3) == vec3(0.0f));
    CHECK(brightPatchIrradiance(split, v.bvh.view(), vec3(-0.3f, 0.5f, 0.0f), vec3(1, 0, 0), 256, 3).x > 1.0f);
}

TEST_CASE("Bright patches at gather points need one origin per point", "[bake]") {
    const Voxelized v = litFloor(50.0f);
    BrightPatchSettings settings;
    settings.factor = 2.0f;
    const BrightPatchSplit split = splitBrightPatches(v.voxels, v.points, settings);
    GatherPoint point;
    point.normal = vec3(0, 1, 0);
    std::vector<vec3> irradiance(2, vec3(0.0f));
    CHECK_THROWS_WITH(addBrightPatchIrradiance({point, point}, {point.position}, split, v.bvh.view(), 16, irradiance),
                      Catch::Contains("1 origins and 2 irradiance values for 2 gather points"));
}
