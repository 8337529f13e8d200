#include "gather/bounces.h"
#include "gather/irradiance_cache.h"
#include "support/cone_scenes.h"
#include "core/error.h"
#include "core/rng.h"

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>

using namespace vl;
using vl::test::SceneBuilder;
using vl::test::VoxelSpec;

namespace {

VoxelSpec surface(const vec3& normal, bool twoSided = false) {
    VoxelSpec spec;
    spec.normal = normal;
    for (int a = 0; a < 3; ++a) {
        if (normal[a] > 0.0f) spec.axisWeights[size_t(2 * a)] = 1.0f;
        if (normal[a] < 0.0f) spec.axisWeights[size_t(2 * a + 1)] = 1.0f;
        if (twoSided && normal[a] != 0.0f) spec.axisWeights[size_t(2 * a)] = spec.axisWeights[size_t(2 * a + 1)] = 1.0f;
    }
    return spec;
}

// A floor one voxel thick at y = 0, x and z in [x0, x1) × [0, n), facing +Y.
void addFloor(SceneBuilder& builder, int x0, int x1, int n, bool twoSided = false) {
    for (int x = x0; x < x1; ++x)
        for (int z = 0; z < n; ++z) builder.add(ivec3(x, 0, z), surface(vec3(0, 1, 0), twoSided));
}


}  // namespace

TEST_CASE("Gather points: one per surface side of each occupied cell, at its voxels' mean centre", "[cone]") {
    const double h = 0.1;
    SceneBuilder builder(h);
    addFloor(builder, 0, 16, 16);
    const VoxelScene scene = builder.build();
    for (int level : {0, 2, 3}) {
        INFO("level " << level);
        const IrradianceCache cache(scene, level);
        const int cells = 16 >> level;
        REQUIRE(cache.points().size() == size_t(cells * cells));
        const float cell = float(h) * float(1 << level);
        for (const GatherPoint& p : cache.points()) {
            CHECK(p.normal == vec3(0, 1, 0));
            CHECK(p.position.y == Approx(0.0f).margin(1e-6));
            // Cell C holds voxels 2^L·C … 2^L·C + 2^L − 1: its mean centre lies (2^L − 1)/2 in.
            const float offset = 0.5f * (float(1 << level) - 1.0f) * float(h);
            const float ix = (p.position.x - offset) / cell, iz = (p.position.z - offset) / cell;
            CHECK(ix == Approx(std::round(ix)).margin(1e-4));
            CHECK(iz == Approx(std::round(iz)).margin(1e-4));
            CHECK(p.turn >= 0.0f);
            CHECK(p.turn < 1.0f);
        }
    }
    // A two-sided floor has a point for each side.
    SceneBuilder twoSided(h);
    addFloor(twoSided, 0, 8, 8, true);
    const IrradianceCache both(twoSided.build(), 2);
    REQUIRE(both.points().size() == 2 * 4);
    size_t up = 0;
    for (const GatherPoint& p : both.points()) up += p.normal.y > 0.0f;
    CHECK(up == 4);
    CHECK_THROWS_AS(IrradianceCache(twoSided.build(), 17), SettingsError);
}

TEST_CASE("A gather point's mass is the root of the share of its cell's columns its layer fills", "[cone]") {
    // Level 3: 8 × 8 columns a cell. A floor over x in [0, 17) leaves a strip one voxel wide in
    // its third cell along x (8 of 64 columns); a floor two voxels deep over [0, 2) × [0, 8)
    // fills 16 columns with 32 voxels, which count once each.
    const double h = 0.1;
    SceneBuilder strip(h);
    addFloor(strip, 0, 17, 16);
    const IrradianceCache cache(strip.build(), 3);
    REQUIRE(cache.points().size() == 6);
    for (const GatherPoint& p : cache.points()) {
        INFO("point at x " << p.position.x);
        CHECK(p.mass == Approx(p.position.x > 1.55f ? std::sqrt(8.0f / 64.0f) : 1.0f).epsilon(1e-6));
    }
    SceneBuilder deep(h);
    for (int y : {0, 1})
        for (int x = 0; x < 2; ++x)
            for (int z = 0; z < 8; ++z) deep.add(ivec3(x, y, z), surface(vec3(0, 1, 0)));
    const IrradianceCache deepCache(deep.build(), 3);
    REQUIRE(deepCache.points().size() == 1);
    CHECK(deepCache.points()[0].mass == Approx(0.5f).epsilon(1e-6));
}

TEST_CASE("Interpolation reproduces constant and linear irradiance on a plane", "[cone]") {
    const double h = 0.1;
    SceneBuilder builder(h);
    addFloor(builder, 0, 32, 32);
    const VoxelScene scene = builder.build();
    const RadianceMips mips = buildRadianceMips(scene);
    IrradianceCache cache(scene, 2);
    cache.link(mips.view());
    // E = a + b·x + c·z: the points sit on a regular grid, where tents sum to one and
    // reproduce linear functions exactly.
    std::vector<vec3> linear;
    for (const GatherPoint& p : cache.points())
        linear.push_back(vec3(1.0f + 2.0f * p.position.x - 0.5f * p.position.z, 1.0f, 0.0f));
    cache.setIrradiance(linear);
    const IrradianceCacheView withLinear = cache.view(mips.view());
    int checked = 0;
    for (float x = 0.6f; x < 2.5f; x += 0.137f)
        for (float z = 0.6f; z < 2.5f; z += 0.161f) {
            vec3 E;
            REQUIRE(interpolateIrradiance(withLinear, vec3(x, 0.0f, z), vec3(0, 1, 0), E));
            CHECK(E.x == Approx(1.0f + 2.0f * x - 0.5f * z).epsilon(1e-4));
            CHECK(E.y == Approx(1.0f).epsilon(1e-5));
            ++checked;
        }
    CHECK(checked > 100);
    // Facing away: nothing applies; far away: nothing applies.
    vec3 E;
    CHECK_FALSE(interpolateIrradiance(withLinear, vec3(1.0f, 0.0f, 1.0f), vec3(0, -1, 0), E));
    CHECK_FALSE(interpolateIrradiance(withLinear, vec3(10.0f, 0.0f, 10.0f), vec3(0, 1, 0), E));
}

TEST_CASE("A wall keeps interpolation on its own side", "[cone]") {
    // Two floors in one plane, x < 16 and x > 16, and a wall at x = 16 standing on them. The
    // left floor's points carry irradiance 1, the right's 0. Without the wall, right-floor
    // receivers by it take some of the left's light; with it, none.
    const double h = 0.1;
    const auto build = [&](bool wall) {
        SceneBuilder builder(h);
        addFloor(builder, 0, 16, 16);
        addFloor(builder, 17, 33, 16);
        if (wall)
            for (int y = 0; y < 8; ++y)
                for (int z = 0; z < 16; ++z) builder.add(ivec3(16, y, z), surface(vec3(1, 0, 0), true));
        return builder.build();
    };
    for (bool wall : {false, true}) {
        INFO((wall ? "with the wall" : "without the wall"));
        const VoxelScene scene = build(wall);
        const RadianceMips mips = buildRadianceMips(scene);
        IrradianceCache cache(scene, 3);
        cache.link(mips.view());
        std::vector<vec3> E;
        for (const GatherPoint& p : cache.points()) E.push_back(vec3(p.position.x < 1.6f ? 1.0f : 0.0f));
        cache.setIrradiance(E);
        const IrradianceCacheView view = cache.view(mips.view());
        float brightest = 0.0f;
        int interpolated = 0;
        for (float x = 1.75f; x < 2.2f; x += 0.05f)
            for (float z = 0.2f; z < 1.4f; z += 0.1f) {
                vec3 value;
                if (interpolateIrradiance(view, vec3(x, 0.0f, z), vec3(0, 1, 0), value)) {
                    brightest = std::max(brightest, value.x);
                    ++interpolated;
                }
            }
        REQUIRE(interpolated > 0);  // the right floor's own points apply
        if (wall)
            CHECK(brightest == 0.0f);
        else
            CHECK(brightest > 0.1f);
    }
}

TEST_CASE("The sides of a two-sided sheet interpolate only their own side", "[cone]") {
    const double h = 0.1;
    SceneBuilder builder(h);
    addFloor(builder, 0, 16, 16, true);
    const VoxelScene scene = builder.build();
    const RadianceMips mips = buildRadianceMips(scene);
    IrradianceCache cache(scene, 2);
    cache.link(mips.view());
    std::vector<vec3> E;
    for (const GatherPoint& p : cache.points()) E.push_back(vec3(p.normal.y > 0.0f ? 3.0f : 0.5f));
    cache.setIrradiance(E);
    const IrradianceCacheView view = cache.view(mips.view());
    vec3 top, bottom;
    REQUIRE(interpolateIrradiance(view, vec3(0.8f, 0.0f, 0.8f), vec3(0, 1, 0), top));
    REQUIRE(interpolateIrradiance(view, vec3(0.8f, 0.0f, 0.8f), vec3(0, -1, 0), bottom));
    CHECK(top.x == Approx(3.0f));
    CHECK(bottom.x == Approx(0.5f));
}

TEST_CASE("A gather point's cone frame turns with the scene about the voxels' centre", "[cone]") {
    // Quarter turns about each axis through the centre: the tangent turns with the point and
    // the turn about the normal stays, so the rotated point's cones are the rotated cones.
    const vec3 centre(-0.05f, -0.05f, -0.05f);
    const float cell = 0.8f;
    Pcg32 rng(11, 3);
    for (int trial = 0; trial < 200; ++trial) {
        vec3 p;
        rng.next2D(p.x, p.y);
        p.z = rng.next1D();
        p = centre + 10.0f * (p - vec3(0.5f));
        vec3 n;
        rng.next2D(n.x, n.y);
        n.z = rng.next1D();
        n = glm::normalize(n - vec3(0.5f));
        vec3 tangent;
        float turn;
        gatherFrame(p, n, centre, cell, tangent, turn);
        CHECK(std::abs(glm::dot(tangent, n)) < 1e-5f);
        CHECK(glm::length(tangent) == Approx(1.0f));
        for (int axis = 0; axis < 3; ++axis) {
            // R: (a, b) → (b, −a) on the two other axes.
            const auto rotate = [&](const vec3& v) {
                vec3 out = v;
                const int a = (axis + 1) % 3, b = (axis + 2) % 3;
                out[a] = v[b];
                out[b] = -v[a];
                return out;
            };
            vec3 rotatedTangent;
            float rotatedTurn;
            gatherFrame(centre + rotate(p - centre), rotate(n), centre, cell, rotatedTangent, rotatedTurn);
            CHECK(glm::distance(rotatedTangent, rotate(tangent)) < 1e-4f);
            CHECK(rotatedTurn == Approx(turn).margin(1e-6));
        }
    }
}

TEST_CASE("The gather gives the same bytes at 1 and 2 threads, and averages its turned sets", "[cone]") {
    const VoxelScene box = vl::test::closedBox(16, 1, vec3(1.0f, 0.8f, 0.6f), vec3(0.5f));
    const RadianceMips mips = buildRadianceMips(box);
    const auto gather = [&](int threads, int turns) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        IrradianceCache cache(box, 2);
        cache.gather(mips.view(), ConeSettings{32}, turns);
        return cache.irradiance();
    };
    const std::vector<vec3> one = gather(1, 2), two = gather(2, 2);
    REQUIRE(one.size() == two.size());
    CHECK(std::memcmp(one.data(), two.data(), one.size() * sizeof(vec3)) == 0);
    // Two turns are the mean of the single sets turned by 0 and ½ turn.
    IrradianceCache cache(box, 2);
    const ConeSet& set = coneSet(32);
    for (size_t q = 0; q < cache.points().size(); ++q) {
        GatherPoint half = cache.points()[q];
        half.turn += 0.5f;
        half.turn -= std::floor(half.turn);
        const vec3 mean = (gatherAtPoint(mips.view(), cache.points()[q], set, ConeSettings{32}, 1) +
                           gatherAtPoint(mips.view(), half, set, ConeSettings{32}, 1)) /
                          2.0f;
        CHECK(glm::distance(one[q], mean) <= 1e-5f * glm::length(mean));
    }
    // Inside a closed box of radiance L every point gathers close to π·L, never more, whatever
    // its turn (the gather's closed-box bound, bounces_test.cpp).
    const std::vector<vec3> single = gather(2, 1);
    for (size_t q = 0; q < one.size(); ++q) {
        CHECK(one[q].x >= 0.84f * kPi);
        CHECK(one[q].x <= kPi * (1.0f + 1e-5f));
        CHECK(single[q].x >= 0.84f * kPi);
        CHECK(single[q].x <= kPi * (1.0f + 1e-5f));
    }
    CHECK_THROWS_AS(gather(1, 0), SettingsError);
}

TEST_CASE("Bounces gathered at coarse points keep the closed-box bound of a gather at every voxel", "[cone]") {
    // The closed-box bound of bounces_test.cpp (added light within [0.84, 1]·ρL0), with the
    // bounce gathered at level-2 points and interpolated at every voxel side.
    const vec3 l0(1.0f, 0.8f, 0.6f);
    const float rho = 0.5f;
    VoxelScene box = vl::test::closedBox(16, 1, l0, vec3(rho));
    ConeSettings settings;
    settings.coneCount = 16;
    propagateBounces(box, BounceSettings{1, 2, BounceTail::None, settings});
    float lowest = 1.0f, highest = 0.0f;
    for (size_t i = 0; i < box.size(); ++i) {
        const vec3 added = (box.radiance[i] - l0) / (rho * l0);
        lowest = glm::min(lowest, glm::min(added.x, glm::min(added.y, added.z)));
        highest = glm::max(highest, maxComponent(added));
    }
    INFO("added light / (ρ L0) from " << lowest << " to " << highest);
    CHECK(lowest >= 0.84f);
    CHECK(highest <= 1.0f + 1e-5f);
}
