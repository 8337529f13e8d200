#include "gather/bounces.h"
#include "support/cone_scenes.h"
#include "core/error.h"
#include "core/rng.h"

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstring>

using namespace vl;
using vl::test::SceneBuilder;
using vl::test::VoxelSpec;

namespace {

ConeSettings settingsFor(int count) {
    ConeSettings s;
    s.coneCount = count;
    return s;
}

}  // namespace

TEST_CASE("one bounce in a closed white box adds albedo times L0", "[cone]") {
    // Every voxel sees walls of radiance L0 all round, so the exact E is π L0 and
    // L1 = L0 + ρ L0; a second bounce gives L0 (1 + ρ + ρ²). The added light is ρ/π·E, so it
    // inherits the gather's shortfall that the closed-box receiver test bounds: at most 10 %
    // on walls and 16 % in corners (6 cones), and never more than the exact value. Here the
    // box is 16 voxels wide and every wall, edge and corner voxel is checked.
    const vec3 l0(1.0f, 0.8f, 0.6f);
    const float rho = 0.5f;
    for (int count : {6, 16}) {
        VoxelScene box = vl::test::closedBox(16, 1, l0, vec3(rho));
        propagateBounces(box, BounceSettings{1, 0, BounceTail::None, settingsFor(count)});
        float lowest = 1.0f, highest = 0.0f, mean = 0.0f;
        for (size_t i = 0; i < box.size(); ++i) {
            const vec3 added = (box.radiance[i] - l0) / (rho * l0);
            lowest = glm::min(lowest, glm::min(added.x, glm::min(added.y, added.z)));
            highest = glm::max(highest, maxComponent(added));
            mean += added.x / float(box.size());
        }
        INFO(count << " cones: added light / (ρ L0) from " << lowest << " to " << highest << ", mean " << mean);
        CHECK(lowest >= 0.84f);
        CHECK(highest <= 1.0f + 1e-5f);
        CHECK(mean >= 0.92f);
    }
    VoxelScene twice = vl::test::closedBox(16, 1, l0, vec3(rho));
    propagateBounces(twice, BounceSettings{2, 0, BounceTail::None, settingsFor(16)});
    const float g = 0.84f;  // the lowest gather fraction allowed above
    for (size_t i = 0; i < twice.size(); ++i) {
        const vec3 ratio = twice.radiance[i] / l0;
        CHECK(ratio.x <= 1.0f + rho + rho * rho + 1e-5f);
        CHECK(ratio.x >= 1.0f + rho * g * (1.0f + rho * g));
    }
}

TEST_CASE("voxels whose normals cancel gather over both sides", "[cone]") {
    // A two-sided sheet across a closed box: normal zero, axis weights on +X and −X. Both
    // half-rooms radiate L, so each face gathers π L from its own half-room.
    const float h = 0.1f;
    const vec3 l0(1.0f);
    VoxelScene scene = [&] {
        VoxelScene box = vl::test::closedBox(17, 1, l0, vec3(0.0f), h);
        SceneBuilder builder(h);
        for (size_t i = 0; i < box.size(); ++i) {
            VoxelSpec spec{box.radiance[i], box.opacity[i], true, box.albedo[i], box.normal[i], box.axisWeights[i],
                           true, box.faceRadiance[i]};
            builder.add(box.coords[i], spec);
        }
        VoxelSpec sheet;
        sheet.radiance = vec3(0.0f);
        sheet.albedo = vec3(1.0f);
        sheet.axisWeights = {0.5f, 0.5f, 0, 0, 0, 0};
        for (int y = 0; y < 17; ++y)
            for (int z = 0; z < 17; ++z) builder.add(ivec3(8, y, z), sheet);
        return builder.build();
    }();
    const RadianceMips mips = buildRadianceMips(scene);
    const ConeSet& set = coneSet(16);
    const vec3 centre = vec3(8.0f) * h;
    const float weights[6] = {0.5f, 0.5f, 0, 0, 0, 0};
    vec3 e[6];
    faceIrradiance(mips.view(), centre, vec3(0.0f), weights, set, ConeSettings{}, e);
    CHECK(e[0].x == Approx(kPi).epsilon(0.1));  // the closed-box gather tolerance
    CHECK(e[1].x == Approx(kPi).epsilon(0.1));
    for (int f = 2; f < 6; ++f) CHECK(e[f] == vec3(0.0f));  // no surface there
    // The +X face gathers along +X whether it is a side of its own (normal zero) or the front
    // of a double-sided surface with normal +X, whose back gathers along −X.
    const float plusX[6] = {1.0f, 0, 0, 0, 0, 0};
    vec3 onlyPlus[6], byNormal[6];
    faceIrradiance(mips.view(), centre, vec3(0.0f), plusX, set, ConeSettings{}, onlyPlus);
    faceIrradiance(mips.view(), centre, vec3(1, 0, 0), weights, set, ConeSettings{}, byNormal);
    CHECK(onlyPlus[0] == byNormal[0]);
    CHECK(onlyPlus[0] == e[0]);
    CHECK(byNormal[1] == e[1]);
    CHECK(onlyPlus[1] == vec3(0.0f));
    // No normal and no weights: nothing to gather from.
    const float none[6] = {};
    vec3 nothing[6];
    faceIrradiance(mips.view(), centre, vec3(0.0f), none, set, ConeSettings{}, nothing);
    for (const vec3& v : nothing) CHECK(v == vec3(0.0f));

    // Through propagateBounces: each face of the sheet (albedo 1, dark) becomes ≈ L0.
    propagateBounces(scene, BounceSettings{1, 0, BounceTail::None, settingsFor(16)});
    for (size_t i = 0; i < scene.size(); ++i)
        if (scene.coords[i].x == 8 && scene.coords[i].y == 8 && scene.coords[i].z == 8) {
            CHECK(scene.faceRadiance[i][0].x == Approx(1.0f).epsilon(0.1));
            CHECK(scene.faceRadiance[i][1].x == Approx(1.0f).epsilon(0.1));
            CHECK(scene.faceRadiance[i][2] == vec3(0.0f));
        }
}

TEST_CASE("a bounce off a thin wall lit on one side stays on that side", "[cone]") {
    // A closed box split by a double-sided wall one voxel thick (normal +X, equal ± weights):
    // the +X half-room radiates L0, the −X half-room is dark, and the wall's faces reflect
    // what they gather. Its +X face gathers from the bright half-room; its −X face sees only
    // dark surfaces, so it stays exactly dark: light does not cross the wall.
    const float h = 0.1f;
    const int n = 17, wallX = 8;
    const vec3 l0(1.0f);
    VoxelScene box = vl::test::closedBox(n, 1, l0, vec3(0.0f), h);
    SceneBuilder builder(h);
    for (size_t i = 0; i < box.size(); ++i) {
        const bool bright = box.coords[i].x > wallX;
        VoxelSpec spec{bright ? l0 : vec3(0.0f), 1.0f, true, vec3(0.0f), box.normal[i], box.axisWeights[i], true, {}};
        for (size_t f = 0; f < 6; ++f) spec.faces[f] = bright ? box.faceRadiance[i][f] : vec3(0.0f);
        builder.add(box.coords[i], spec);
    }
    VoxelSpec wall;
    wall.albedo = vec3(1.0f);
    wall.normal = vec3(1, 0, 0);
    wall.axisWeights = {1, 1, 0, 0, 0, 0};
    wall.directional = true;
    for (int y = -1; y <= n; ++y)
        for (int z = -1; z <= n; ++z) builder.add(ivec3(wallX, y, z), wall);
    VoxelScene scene = builder.build();
    propagateBounces(scene, BounceSettings{1, 0, BounceTail::None, settingsFor(16)});
    size_t litBack = 0, darkFront = 0, inside = 0;
    for (size_t i = 0; i < scene.size(); ++i) {
        const ivec3 c = scene.coords[i];
        if (c.x != wallX || c.y < 2 || c.y > n - 3 || c.z < 2 || c.z > n - 3) continue;
        ++inside;
        litBack += scene.faceRadiance[i][1] == vec3(0.0f) ? 0 : 1;
        darkFront += scene.faceRadiance[i][0].x > 0.5f ? 0 : 1;
    }
    CHECK(inside == size_t((n - 4) * (n - 4)));
    CHECK(litBack == 0);
    CHECK(darkFront == 0);
}

TEST_CASE("propagateBounces gives the same bytes with 1 and 2 threads", "[cone]") {
    // A room with random radiance, albedo and normals, partial opacity: work spread unevenly.
    SceneBuilder builder(0.1);
    for (int i = 0; i < 4000; ++i) {
        Pcg32 rng = Pcg32::forItem(uint64_t(i), 0, 41);
        const ivec3 c(int(rng.nextU32() % 20), int(rng.nextU32() % 20), int(rng.nextU32() % 20));
        VoxelSpec spec;
        spec.solid = rng.next1D() < 0.5f;
        spec.opacity = 0.1f + 0.9f * rng.next1D();
        const float r = rng.next1D();
        spec.radiance = vec3(r, rng.next1D(), 0.5f);
        spec.albedo = vec3(0.8f * rng.next1D());
        const float nx = rng.next1D() - 0.5f;
        spec.normal = i % 10 == 0 ? vec3(0.0f) : glm::normalize(vec3(nx, rng.next1D() - 0.5f, 0.3f));
        spec.axisWeights = {0.3f, 0.7f, 0.0f, 0.1f, 0.0f, 0.0f};
        builder.add(c, spec);
    }
    const VoxelScene scene = builder.build();
    const auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        VoxelScene copy = scene;
        propagateBounces(copy, BounceSettings{2, 0, BounceTail::None, settingsFor(6)});
        return copy.radiance;
    };
    const std::vector<vec3> one = run(1), two = run(2);
    REQUIRE(one.size() == two.size());
    CHECK(std::memcmp(one.data(), two.data(), one.size() * sizeof(vec3)) == 0);
    // The bounce changed something, so the comparison is not vacuous.
    CHECK(std::memcmp(one.data(), scene.radiance.data(), one.size() * sizeof(vec3)) != 0);
}

TEST_CASE("propagateBounces refuses bad settings and missing channels", "[cone]") {
    VoxelScene box = vl::test::closedBox(4, 1, vec3(1.0f), vec3(0.5f));
    CHECK_THROWS_AS(propagateBounces(box, BounceSettings{-1, 0, BounceTail::None, ConeSettings{}}), SettingsError);
    CHECK_THROWS_AS(propagateBounces(box, BounceSettings{5000, 0, BounceTail::None, ConeSettings{}}), SettingsError);
    ConeSettings bad;
    bad.apertureDegrees = -10.0f;
    CHECK_THROWS_WITH(propagateBounces(box, BounceSettings{1, 0, BounceTail::None, bad}), Catch::Contains("aperture"));
    VoxelScene unlit = box;
    unlit.radiance.clear();
    CHECK_THROWS_WITH(propagateBounces(unlit, BounceSettings{1, 0, BounceTail::None, ConeSettings{}}), Catch::Contains("radiance"));
    const std::vector<vec3> before = box.radiance;
    propagateBounces(box, BounceSettings{0, 0, BounceTail::None, ConeSettings{}});
    CHECK(box.radiance == before);
}

TEST_CASE("The geometric tail takes a closed box's bounces to their limit", "[cone]") {
    // A closed box of uniform albedo ρ whose every voxel gathers the same fraction g of π·L:
    // each bounce adds ρg times the last, so L_∞ = L0 / (1 − ρg). Two bounces and the tail
    // (from the ratio of the last two) land on that limit, where two bounces alone fall short
    // by (ρg)³/(1 − ρg), and 24 bounces agree with the tail.
    const vec3 l0(1.0f);
    const float rho = 0.5f;
    const auto bake = [&](int bounces, BounceTail tail) {
        VoxelScene box = vl::test::closedBox(16, 1, l0, vec3(rho));
        ConeSettings settings;
        settings.coneCount = 16;
        propagateBounces(box, BounceSettings{bounces, 2, tail, settings});
        double mean = 0.0;
        for (const vec3& r : box.radiance) mean += r.x / double(box.size());
        return mean;
    };
    const double two = bake(2, BounceTail::None), twoWithTail = bake(2, BounceTail::Geometric);
    const double many = bake(24, BounceTail::None);
    INFO("mean L after 2 bounces " << two << ", with the tail " << twoWithTail << ", after 24 " << many);
    CHECK(many > two * 1.05);                          // the tail holds real light
    CHECK(twoWithTail == Approx(many).epsilon(0.01));  // and the extrapolation finds it
    CHECK(many < 1.0 / (1.0 - rho) + 1e-6);            // never more than a perfect gather gives
}

TEST_CASE("The mips and gather points propagateBounces hands back are those of its result", "[cone]") {
    // The bake takes the bounces' own mips, relit, instead of building them again: every
    // level's texels and isotropic values must be the bytes buildRadianceMips gives for the
    // bounced voxels, or the final gather would read other light than the voxels hold.
    VoxelScene box = vl::test::closedBox(16, 1, vec3(1.0f, 0.8f, 0.6f), vec3(0.5f));
    const Bounced bounced = propagateBounces(box, BounceSettings{3, 1, BounceTail::Geometric, settingsFor(6)});
    const RadianceMips& handed = bounced.mips;
    const IrradianceCache& handedPoints = bounced.points;
    const RadianceMips built = buildRadianceMips(box);
    // The gather points likewise: the same points, linked to the same neighbours.
    IrradianceCache builtPoints(box, 1);
    builtPoints.link(built.view());
    REQUIRE(handedPoints.points().size() == builtPoints.points().size());
    REQUIRE(!builtPoints.points().empty());
    const IrradianceCacheView a = handedPoints.view(handed.view()), b = builtPoints.view(built.view());
    REQUIRE(a.pointCount == b.pointCount);
    CHECK(std::equal(a.neighbourBegin, a.neighbourBegin + a.pointCount + 1, b.neighbourBegin));
    CHECK(std::equal(a.neighbours, a.neighbours + a.neighbourBegin[a.pointCount], b.neighbours));
    for (size_t q = 0; q < builtPoints.points().size(); ++q) {
        CHECK(handedPoints.points()[q].position == builtPoints.points()[q].position);
        CHECK(handedPoints.points()[q].normal == builtPoints.points()[q].normal);
    }
    REQUIRE(handed.levelCount() == built.levelCount());
    REQUIRE(built.levelCount() > 2);
    for (int k = 0; k < built.levelCount(); ++k) {
        const MipLevel& a = handed.level(k);
        const MipLevel& b = built.level(k);
        REQUIRE(a.texels.size() == b.texels.size());
        CHECK(a.coords == b.coords);
        CHECK(a.values == b.values);
        bool same = true;
        for (size_t t = 0; t < a.texels.size() && same; ++t)
            same = a.texels[t].radiance == b.texels[t].radiance && a.texels[t].alpha == b.texels[t].alpha &&
                   a.texels[t].coverage == b.texels[t].coverage && a.texels[t].density == b.texels[t].density;
        INFO("level " << k);
        CHECK(same);
    }
    // No bounces: nothing is handed back and the caller builds the mips itself.
    const Bounced none = propagateBounces(box, BounceSettings{0, 1, BounceTail::None, settingsFor(6)});
    CHECK(none.mips.levelCount() == 0);
}
