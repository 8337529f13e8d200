#include "cone/cone_trace.h"
#include "cone/radiance_mips.h"
#include "support/cone_scenes.h"
#include "core/error.h"
#include "core/rng.h"

#include <catch2/catch.hpp>

#include <map>
#include <tuple>

using namespace vl;
using vl::test::SceneBuilder;
using vl::test::VoxelSpec;

namespace {

uint32_t below(Pcg32& rng, uint32_t n) { return rng.nextU32() % n; }

// Random sparse voxels in [lo, lo + extent)³ whose α and radiance are small dyadic
// fractions: every product, sum of ≤ 8 and division by 8 is then exact in float.
VoxelScene dyadicScene(int count, ivec3 lo, int extent, uint64_t salt) {
    SceneBuilder builder(0.25);
    for (int i = 0; i < count; ++i) {
        Pcg32 rng = Pcg32::forItem(uint64_t(i), 0, salt);
        const ivec3 c = lo + ivec3(int(below(rng, uint32_t(extent))), int(below(rng, uint32_t(extent))),
                                   int(below(rng, uint32_t(extent))));
        VoxelSpec spec;
        spec.solid = below(rng, 4) == 0;
        spec.opacity = float(1 + below(rng, 8)) / 8.0f;
        spec.radiance = vec3(float(below(rng, 64)), float(below(rng, 64)), float(below(rng, 64))) / 16.0f;
        builder.add(c, spec);
    }
    return builder.build();
}

vec4 levelSum(const MipLevel& level) {
    vec4 sum(0.0f);
    for (const vec4& v : level.values) sum += v;
    return sum;
}

}  // namespace

TEST_CASE("mip averaging conserves alpha-weighted radiance times volume exactly", "[cone]") {
    const VoxelScene scene = dyadicScene(3000, ivec3(-20, -7, 3), 40, 11);
    const RadianceMips mips = buildRadianceMips(scene);
    REQUIRE(mips.levelCount() >= 5);

    // Level 0 by hand from the channels: α = 1 for solid voxels.
    vec4 expected(0.0f);
    for (size_t i = 0; i < scene.size(); ++i) {
        const float alpha = scene.solid[i] ? 1.0f : scene.opacity[i];
        expected += vec4(alpha * scene.radiance[i], alpha);
    }
    CHECK(levelSum(mips.level(0)) == expected);
    // Volume of a level-k voxel is 8^k level-0 voxels.
    for (int k = 1; k < mips.levelCount(); ++k) {
        INFO("level " << k);
        CHECK(levelSum(mips.level(k)) * float(1 << (3 * k)) == expected);
    }
    // The last level is small: at most 8 voxels or 2 voxels across.
    const MipLevel& last = mips.level(mips.levelCount() - 1);
    CHECK(last.coords.size() <= 8);
}

TEST_CASE("mip levels are sparse and their voxels cover exactly their children", "[cone]") {
    const VoxelScene scene = dyadicScene(500, ivec3(-9, -9, -9), 18, 5);
    const RadianceMips mips = buildRadianceMips(scene);
    for (int k = 1; k < mips.levelCount(); ++k) {
        const MipLevel& children = mips.level(k - 1);
        const MipLevel& parents = mips.level(k);
        // Children grouped by floor(c / 2), independently of the implementation's sort.
        std::map<std::tuple<int, int, int>, vec4> sums;
        for (size_t i = 0; i < children.coords.size(); ++i) {
            const ivec3 p = ivec3(glm::floor(vec3(children.coords[i]) / 2.0f));
            sums[std::make_tuple(p.x, p.y, p.z)] += children.values[i];
        }
        REQUIRE(parents.coords.size() == sums.size());
        size_t i = 0;
        for (const auto& [key, sum] : sums) {  // std::map iterates in (x, y, z) order
            CHECK(parents.coords[i] == ivec3(std::get<0>(key), std::get<1>(key), std::get<2>(key)));
            CHECK(parents.values[i] == sum / 8.0f);
            ++i;
        }
    }
}

TEST_CASE("a level-k voxel centre is the centroid of its level-0 voxels", "[cone]") {
    const float h = 0.25f;
    for (int k = 0; k < 5; ++k)
        for (const ivec3 parent : {ivec3(0, 0, 0), ivec3(-3, 2, 7), ivec3(5, -1, -4)}) {
            // Mean of the level-0 centres it covers: 2^k·I + j, j = 0 … 2^k − 1 per axis.
            const int n = 1 << k;
            vec3 centroid(0.0f);
            for (int j = 0; j < n; ++j) centroid += vec3(parent * n + ivec3(j)) * h;
            centroid /= float(n);
            CHECK(glm::distance(mipVoxelCentre(parent, h, k), centroid) < 1e-5f);
            CHECK(glm::distance(mipIndexPosition(centroid, h, k), vec3(parent)) < 1e-5f);
        }

    // The NanoVDB grids carry the same transform (what a VDB tool and worldToIndex see).
    const VoxelScene scene = dyadicScene(300, ivec3(-8, -8, -8), 16, 3);
    const RadianceMips mips = buildRadianceMips(scene);
    for (int k = 0; k < mips.levelCount(); ++k) {
        const MipLevel& level = mips.level(k);
        const ivec3 c = level.coords.front();
        const nanovdb::Vec3d w = mips.indexGrid(k)->indexToWorld(nanovdb::Vec3d(c.x, c.y, c.z));
        CHECK(glm::distance(vec3(float(w[0]), float(w[1]), float(w[2])), mipVoxelCentre(c, float(scene.voxelSize), k)) <
              1e-5f);
        CHECK(mips.indexGrid(k)->voxelSize()[0] == Approx(scene.voxelSize * (1 << k)));
        CHECK(mips.indexGrid(k)->tree().getValue(nanovdb::Coord(c.x, c.y, c.z)) == 0);
    }
}

TEST_CASE("sampling at a level-k voxel centre returns the average of its children", "[cone]") {
    // The parent's centre is the corner its 8 children share at level k−1, so the trilinear
    // sample there weighs each child 1/8 (absent ones zero); at level k it is the parent's
    // own texel. Checked for the isotropic average and for every direction of travel.
    const VoxelScene scene = dyadicScene(2000, ivec3(-16, -16, -16), 32, 17);
    const RadianceMips mips = buildRadianceMips(scene);
    const MipView view = mips.view();
    const float h = view.voxelSize;
    const vec3 axes[6] = {vec3(1, 0, 0), vec3(-1, 0, 0), vec3(0, 1, 0), vec3(0, -1, 0), vec3(0, 0, 1), vec3(0, 0, -1)};
    for (int k = 1; k < mips.levelCount(); ++k) {
        const MipLevel& children = mips.level(k - 1);
        std::map<std::tuple<int, int, int>, size_t> childIndex;
        for (size_t i = 0; i < children.coords.size(); ++i) {
            const ivec3& c = children.coords[i];
            childIndex[std::make_tuple(c.x, c.y, c.z)] = i;
        }
        const MipLevel& level = mips.level(k);
        for (size_t i = 0; i < level.coords.size(); i += 7) {
            const ivec3 parent = level.coords[i];
            const vec3 centre = mipVoxelCentre(parent, h, k);
            INFO("level " << k << " voxel " << parent.x << " " << parent.y << " " << parent.z);
            vec4 isotropic(0.0f);
            for (int face = 0; face < 6; ++face) {
                vec4 average(0.0f);
                for (int d = 0; d < 8; ++d) {
                    const ivec3 c = 2 * parent + ivec3(d & 1, (d >> 1) & 1, d >> 2);
                    const auto it = childIndex.find(std::make_tuple(c.x, c.y, c.z));
                    if (it == childIndex.end()) continue;
                    const MipTexel& t = children.texels[it->second * size_t(children.facesPerVoxel) + size_t(face)];
                    average += vec4(t.radiance, t.alpha) / 8.0f;
                    if (face == 0) isotropic += children.values[it->second] / 8.0f;
                }
                const MipSample fromChildren =
                    sampleMipLevel(view.levels[k - 1], mipIndexPosition(centre, h, k - 1), axes[face]);
                CHECK(glm::distance(vec4(fromChildren.radiance, fromChildren.alpha), average) <
                      1e-5f * (1.0f + glm::length(average)));
                const MipSample atLevel = sampleMipLevel(view.levels[k], mipIndexPosition(centre, h, k), axes[face]);
                const MipTexel& own = level.texels[i * kFaceCount + size_t(face)];
                CHECK(glm::distance(vec4(atLevel.radiance, atLevel.alpha), vec4(own.radiance, own.alpha)) < 1e-5f);
            }
            CHECK(level.values[i] == isotropic);
        }
    }
}

TEST_CASE("directional texels composite children front to back along their axis", "[cone]") {
    // Two voxels stacked along x inside one level-1 parent: a half-transparent red one in
    // front (lower x) and an opaque green one behind.
    SceneBuilder builder(0.5);
    VoxelSpec red;
    red.solid = false;
    red.opacity = 0.5f;
    red.radiance = vec3(1, 0, 0);
    VoxelSpec green;
    green.radiance = vec3(0, 1, 0);
    builder.add(ivec3(0, 0, 0), red);
    builder.add(ivec3(1, 0, 0), green);
    for (int x = 0; x < 10; ++x) builder.add(ivec3(x, 9, 9), green);  // more than 8 voxels: level 1 is built
    const RadianceMips mips = buildRadianceMips(builder.build());
    REQUIRE(mips.levelCount() >= 2);
    const MipLevel& level = mips.level(1);
    REQUIRE(level.coords.front() == ivec3(0));
    const MipTexel* t = &level.texels[0];
    // Travelling +X: red (α ½) then green: c = ½·red + ½·green, α = 1; one of 4 pairs.
    CHECK(t[kFacePosX].radiance == vec3(0.5f, 0.5f, 0.0f) / 4.0f);
    CHECK(t[kFacePosX].alpha == 0.25f);
    // Travelling −X: green first hides red.
    CHECK(t[kFaceNegX].radiance == vec3(0.0f, 1.0f, 0.0f) / 4.0f);
    CHECK(t[kFaceNegX].alpha == 0.25f);
    // Travelling +Y: both are separate pairs, each seen on its own.
    CHECK(t[kFacePosY].radiance == vec3(0.5f, 1.0f, 0.0f) / 4.0f);
    CHECK(t[kFacePosY].alpha == 1.5f / 4.0f);
    CHECK(t[kFacePosY].density == Approx(-std::log(1.0f - 1.5f / 4.0f)));
    // The isotropic average: (½·red + green, ½ + 1) / 8.
    CHECK(level.values[0] == vec4(0.5f, 1.0f, 0.0f, 1.5f) / 8.0f);

    // A uniform medium: α_k = 1 − (1 − α₀)^(2^k) along every axis (Beer–Lambert).
    SceneBuilder medium(0.5);
    VoxelSpec fog;
    fog.solid = false;
    fog.opacity = 0.2f;
    for (int x = 0; x < 8; ++x)
        for (int y = 0; y < 8; ++y)
            for (int z = 0; z < 8; ++z) medium.add(ivec3(x, y, z), fog);
    const RadianceMips fogMips = buildRadianceMips(medium.build());
    REQUIRE(fogMips.levelCount() == 3);
    for (int k = 1; k < 3; ++k)
        for (const MipTexel& texel : fogMips.level(k).texels)
            CHECK(texel.alpha == Approx(1.0 - std::pow(0.8, 1 << k)).epsilon(1e-5));
}

TEST_CASE("sampling between levels is linear in the level", "[cone]") {
    const VoxelScene scene = dyadicScene(800, ivec3(0, 0, 0), 20, 23);
    const RadianceMips mips = buildRadianceMips(scene);
    const MipView view = mips.view();
    const vec3 p = vec3(7.3f, 9.1f, 11.6f) * view.voxelSize;
    const vec3 dir = glm::normalize(vec3(1, -2, 3));
    const float step = 0.7f * view.voxelSize;
    const vec4 a = coneSegment(view, p, dir, 1.0f, step), b = coneSegment(view, p, dir, 2.0f, step);
    REQUIRE(a.w > 0.0f);
    const vec4 mid = coneSegment(view, p, dir, 1.25f, step);
    CHECK(glm::distance(mid, 0.75f * a + 0.25f * b) < 1e-5f);
    // Beyond the chain the coarsest level is used.
    CHECK(coneSegment(view, p, dir, 40.0f, step) == coneSegment(view, p, dir, float(view.levelCount - 1), step));
}

TEST_CASE("level 0 built alone and completed later is the whole pyramid", "[cone]") {
    // The gathers by rays build level 0 alone (buildLevelZeroMips); grids.vdb and cones add
    // the coarser levels after (addParentLevels), from level 0 as the last relight left it.
    // That must be the pyramid buildRadianceMips makes of the same radiance, texel for texel.
    const VoxelScene v = dyadicScene(400, ivec3(-8), 24, 7);
    REQUIRE(v.axisWeights.size() == v.size());
    std::vector<FaceRadiance> faces(v.size());
    for (size_t i = 0; i < v.size(); ++i)
        for (size_t f = 0; f < 6; ++f)
            faces[i][f] = v.axisWeights[i][f] > 0.0f ? vec3(0.1f * float(f + 1), float(i % 7), 0.5f) : vec3(0.0f);
    std::vector<vec3> radiance(v.size());
    for (size_t i = 0; i < v.size(); ++i) radiance[i] = faceWeightedMean(faces[i].data(), v.axisWeights[i].data());
    const RadianceMips whole = buildRadianceMips(v, radiance, faces);
    REQUIRE(whole.levelCount() > 2);
    // Built first from other light, then relit, as the bounces do.
    std::vector<FaceRadiance> dark(v.size(), FaceRadiance{});
    RadianceMips completed = buildLevelZeroMips(v, std::vector<vec3>(v.size(), vec3(0.0f)), dark);
    CHECK(completed.levelCount() == 1);
    completed.relight(v, radiance, faces);
    completed.addParentLevels();
    REQUIRE(completed.levelCount() == whole.levelCount());
    for (int k = 0; k < whole.levelCount(); ++k) {
        INFO("level " << k);
        const MipLevel& a = whole.level(k);
        const MipLevel& b = completed.level(k);
        REQUIRE(a.coords == b.coords);
        REQUIRE(a.texels.size() == b.texels.size());
        for (size_t t = 0; t < a.texels.size(); ++t) {
            CHECK(a.texels[t].radiance == b.texels[t].radiance);
            CHECK(a.texels[t].alpha == b.texels[t].alpha);
            CHECK(a.texels[t].density == b.texels[t].density);
            CHECK(a.texels[t].coverage == b.texels[t].coverage);
        }
        REQUIRE(a.values.size() == b.values.size());
        for (size_t i = 0; i < a.values.size(); ++i) CHECK(a.values[i] == b.values[i]);
        CHECK(completed.indexGrid(k)->activeVoxelCount() == whole.indexGrid(k)->activeVoxelCount());
    }
}

TEST_CASE("mip grids for the vdb file hold every level", "[cone]") {
    const VoxelScene scene = dyadicScene(200, ivec3(0, 0, 0), 12, 29);
    const RadianceMips mips = buildRadianceMips(scene);
    const std::vector<ExtraGrid> grids = mipGridsForFile(mips);
    REQUIRE(grids.size() == size_t(2 * mips.levelCount()));
    for (int k = 0; k < mips.levelCount(); ++k) {
        const ExtraGrid& radiance = grids[size_t(2 * k)];
        const ExtraGrid& opacity = grids[size_t(2 * k + 1)];
        CHECK(radiance.name == "radiance_mip" + std::to_string(k));
        CHECK(opacity.name == "opacity_mip" + std::to_string(k));
        CHECK(radiance.isVector());
        CHECK_FALSE(opacity.isVector());
        CHECK(radiance.voxelSize == Approx(scene.voxelSize * (1 << k)));
        const MipLevel& level = mips.level(k);
        REQUIRE(radiance.coords == level.coords);
        REQUIRE(opacity.scalars.size() == level.values.size());
        for (size_t i = 0; i < level.values.size(); ++i) {
            CHECK(radiance.vectors[i] == vec3(level.values[i]));
            CHECK(opacity.scalars[i] == level.values[i].w);
        }
    }
}

TEST_CASE("buildRadianceMips refuses unlit or broken channels", "[cone]") {
    SceneBuilder builder(0.1);
    builder.add(ivec3(0), VoxelSpec{});
    builder.add(ivec3(1, 0, 0), VoxelSpec{});
    VoxelScene scene = builder.build();

    VoxelScene unlit = scene;
    unlit.radiance.clear();
    CHECK_THROWS_WITH(buildRadianceMips(unlit), Catch::Contains("run the lighting stage first"));

    VoxelScene nan = scene;
    nan.radiance[1].y = std::nanf("");
    CHECK_THROWS_AS(buildRadianceMips(nan), InputError);
    CHECK_THROWS_WITH(buildRadianceMips(nan), Catch::Contains("voxel 1 (1, 0, 0)"));

    VoxelScene badOpacity = scene;
    badOpacity.solid[0] = 0;
    badOpacity.opacity[0] = 1.5f;
    CHECK_THROWS_WITH(buildRadianceMips(badOpacity), Catch::Contains("opacity of voxel 0"));

    VoxelScene far = scene;
    far.coords[1] = ivec3(1 << 21, 0, 0);
    CHECK_THROWS_WITH(buildRadianceMips(far), Catch::Contains("beyond"));

    VoxelScene empty;
    empty.voxelSize = 0.1;
    const RadianceMips none = buildRadianceMips(empty);
    CHECK(none.levelCount() == 0);
    const ConeResult cone = traceCone(none.view(), vec3(0.0f), vec3(1, 0, 0), 0.3f, 0.5f, 0.0f);
    CHECK(cone.radiance == vec3(0.0f));
    CHECK(cone.occlusion == 0.0f);
}
