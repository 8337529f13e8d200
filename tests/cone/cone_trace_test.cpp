#include "cone/cone_trace.h"
#include "support/cone_scenes.h"
#include "core/rng.h"
#include "core/sampling.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;
using vl::test::SceneBuilder;
using vl::test::VoxelSpec;

namespace {

// A cube of `n`³ voxels of opacity α (not solid) and radiance L.
VoxelScene uniformMedium(int n, float alpha, vec3 radiance, double h) {
    SceneBuilder builder(h);
    VoxelSpec spec;
    spec.solid = false;
    spec.opacity = alpha;
    spec.radiance = radiance;
    for (int x = 0; x < n; ++x)
        for (int y = 0; y < n; ++y)
            for (int z = 0; z < n; ++z) builder.add(ivec3(x, y, z), spec);
    return builder.build();
}

// A wall of solid voxels with x in [x0, x0 + thickness), |y|, |z| ≤ halfSize.
void addWall(SceneBuilder& builder, int x0, int thickness, int halfSize, vec3 radiance) {
    VoxelSpec spec;
    spec.radiance = radiance;
    for (int x = x0; x < x0 + thickness; ++x)
        for (int y = -halfSize; y <= halfSize; ++y)
            for (int z = -halfSize; z <= halfSize; ++z) builder.add(ivec3(x, y, z), spec);
}

ConeSettings settingsFor(int count) {
    ConeSettings s;
    s.coneCount = count;
    return s;
}

}  // namespace

TEST_CASE("a narrow cone through a uniform medium follows Beer-Lambert", "[cone]") {
    // Diameter 2·t·tan θ stays under one voxel over the 16 voxels marched, so every sample is
    // at level 0 and T = (1 − α)^(distance / h) exactly (the step correction composes).
    const float h = 0.1f, alpha = 0.1f;
    const vec3 radiance(2.0f, 1.0f, 0.5f);
    const MipView view = [&] {
        static const RadianceMips mips = buildRadianceMips(uniformMedium(48, alpha, radiance, h));
        return mips.view();
    }();
    for (const vec3 dir : {vec3(1, 0, 0), glm::normalize(vec3(1, -1, 1)), glm::normalize(vec3(0.3f, 0.5f, -0.8f))}) {
        for (float distanceVoxels : {4.0f, 9.5f, 16.0f}) {
            const vec3 apex = vec3(24.0f, 24.0f, 24.0f) * h;
            const ConeResult cone = traceCone(view, apex, dir, 0.01f, 0.5f, distanceVoxels * h);
            const float transmittance = std::pow(1.0f - alpha, distanceVoxels);
            INFO("distance " << distanceVoxels << " voxels");
            CHECK(1.0f - cone.occlusion == Approx(transmittance).epsilon(1e-4));
            // A medium of one colour composites to that colour times its opacity.
            CHECK(glm::distance(cone.radiance, radiance * cone.occlusion) < 1e-4f);
        }
    }
    // Halving the step changes nothing: the opacity correction makes it step-independent.
    const vec3 apex = vec3(24.0f) * h;
    const ConeResult coarse = traceCone(view, apex, vec3(0, 1, 0), 0.01f, 1.0f, 12.0f * h);
    const ConeResult fine = traceCone(view, apex, vec3(0, 1, 0), 0.01f, 0.1f, 12.0f * h);
    CHECK(coarse.occlusion == Approx(fine.occlusion).epsilon(1e-4));
}

TEST_CASE("a wide cone through a uniform medium follows Beer-Lambert too", "[cone]") {
    // Coarse texels compose α along their axis, so every level of a uniform medium has the
    // same optical depth per metre and T = (1 − α)^(distance/h) whatever the cone's width.
    // The cone stays ≥ 2 coarse voxels inside the medium, away from its edges.
    const float h = 0.1f, alpha = 0.05f;
    static const RadianceMips mips = buildRadianceMips(uniformMedium(64, alpha, vec3(1.0f), h));
    const MipView view = mips.view();
    for (float tanHalf : {0.1f, 0.2f})
        for (const vec3 dir : {vec3(1, 0, 0), glm::normalize(vec3(1, 1, 0.5f))}) {
            const float distance = 16.0f * h;
            const ConeResult cone = traceCone(view, vec3(24.0f) * h, dir, tanHalf, 0.5f, distance);
            INFO("tan θ " << tanHalf << ": T = " << 1.0f - cone.occlusion);
            CHECK(1.0f - cone.occlusion == Approx(std::pow(1.0f - alpha, 16.0f)).epsilon(1e-4));
        }
}

TEST_CASE("a cone toward empty space gathers nothing", "[cone]") {
    const float h = 0.1f;
    SceneBuilder builder(h);
    addWall(builder, 10, 1, 16, vec3(5.0f));
    addWall(builder, -10, 1, 16, vec3(0.0f));  // dark wall behind: the grid spans both
    static const RadianceMips mips = buildRadianceMips(builder.build());
    const MipView view = mips.view();
    // Inside the grid, away from the bright wall toward the dark one: occluded, but dark.
    const ConeResult toDark = traceCone(view, vec3(0.0f), vec3(-1, 0, 0), 0.3f, 0.5f, 0.0f);
    CHECK(toDark.radiance == vec3(0.0f));
    CHECK(toDark.occlusion > 0.9f);
    // Along the walls through the empty middle, out of the grid.
    const ConeResult sideways = traceCone(view, vec3(0.0f), vec3(0, 0, 1), 0.05f, 0.5f, 0.0f);
    CHECK(sideways.radiance == vec3(0.0f));
    CHECK(sideways.occlusion == 0.0f);
    // From outside the grid, pointing away.
    const ConeResult away = traceCone(view, vec3(3.0f, 0.0f, 0.0f), vec3(1, 0, 0), 0.5f, 0.5f, 0.0f);
    CHECK(away.radiance == vec3(0.0f));
    // From outside the grid, pointing at the bright wall: it is seen (the march skips ahead).
    const ConeResult back = traceCone(view, vec3(50.0f, 0.0f, 0.0f), vec3(-1, 0, 0), 0.01f, 0.5f, 0.0f);
    CHECK(back.radiance.x == Approx(5.0f * back.occlusion));
    CHECK(back.occlusion > 0.99f);
    // maxDistance short of the wall: nothing.
    const ConeResult capped = traceCone(view, vec3(0.0f), vec3(1, 0, 0), 0.05f, 0.5f, 5.0f * h);
    CHECK(capped.radiance == vec3(0.0f));
}

TEST_CASE("a receiver inside a closed radiating box gets pi times L", "[cone]") {
    // Every direction ends on a wall of radiance L, so the exact E is π L. Cones can only
    // fall short of it (each composites at most L, and stops at A ≥ 0.99), never exceed it.
    // How far short is the price of the coarse levels: a wide cone's footprint is as large
    // as the box, and the coarse voxels around the box's edges are partly empty, so it sees
    // the walls as partly transparent there. Measured (E/πL, 6/16/32 cones): centre facing
    // up 0.94/0.97/0.95, centre facing (1, −2, ½) 0.91/0.96/0.95, on the floor
    // 0.97/0.94/0.94, by a wall 0.94/0.96/0.97, corner 0.85/0.93/0.96. Tolerances: 10 % in
    // the box, 16 % in a corner (6 cones).
    const float h = 0.1f;
    const vec3 radiance(1.0f, 0.5f, 0.25f);
    static const RadianceMips mips = buildRadianceMips(vl::test::closedBox(32, 1, radiance, vec3(0.0f), h));
    const MipView view = mips.view();
    struct Receiver {
        vec3 p, n;
        float minFraction;
    };
    const Receiver receivers[] = {
        {vl::test::boxCentre(32, h), vec3(0, 0, 1), 0.90f},
        {vl::test::boxCentre(32, h), glm::normalize(vec3(1, -2, 0.5f)), 0.90f},
        {vec3(15.5f, 16.0f, -1.0f) * h, vec3(0, 0, 1), 0.90f},   // on the floor voxels' centres
        {vec3(0.0f, 16.0f, -0.5f) * h, vec3(0, 0, 1), 0.90f},    // on the floor surface by a wall
        {vec3(31.5f, 31.5f, 31.5f) * h, glm::normalize(vec3(-1.0f)), 0.84f},  // in a corner
    };
    for (int count : {6, 16, 32}) {
        const ConeSet& set = coneSet(count);
        for (const Receiver& r : receivers) {
            float occlusion = 0.0f;
            const vec3 e = coneTraceIrradiance(view, r.p, r.n, set, settingsFor(count), &occlusion);
            const vec3 fraction = e / (kPi * radiance);
            INFO(count << " cones, receiver " << r.p.x << " " << r.p.y << " " << r.p.z << ": E/(πL) = " << fraction.x
                       << ", occlusion " << occlusion);
            CHECK(fraction.x >= r.minFraction);
            CHECK(maxComponent(fraction) <= 1.0f + 1e-5f);
            // One colour everywhere: E is that colour times the cosine-weighted occlusion.
            CHECK(glm::distance(fraction, vec3(occlusion)) < 1e-4f);
        }
    }
}

TEST_CASE("an opaque wall between a receiver and a bright wall cuts the light", "[cone]") {
    // Bright wall (L = 1) at x = 24, a dark solid wall of 1 or 2 voxels at x = 12, receivers
    // facing it at 2 and 6 voxels in front. Leak ratio = E with the dark wall / E without.
    const float h = 0.1f;
    const vec3 bright(1.0f);
    const auto irradiance = [&](int blockerThickness, float receiverX, int count) {
        SceneBuilder builder(h);
        addWall(builder, 24, 1, 40, bright);
        if (blockerThickness > 0) addWall(builder, 12, blockerThickness, 40, vec3(0.0f));
        const RadianceMips mips = buildRadianceMips(builder.build());
        return coneTraceIrradiance(mips.view(), vec3(receiverX, 0.0f, 0.0f) * h, vec3(1, 0, 0), coneSet(count),
                                   settingsFor(count))
            .x;
    };
    for (int count : {6, 16, 32})
        for (float receiverX : {10.0f, 6.0f}) {
            const float open = irradiance(0, receiverX, count);
            REQUIRE(open > 0.5f * kPi);
            for (int thickness : {1, 2}) {
                const float leak = irradiance(thickness, receiverX, count) / open;
                INFO(count << " cones, receiver " << 12.0f - receiverX << " voxels before a wall " << thickness
                           << " voxels thick: leak ratio " << leak);
                WARN("leak ratio " << leak << " (" << count << " cones, wall " << thickness << " voxel(s), receiver "
                                   << 12.0f - receiverX << " voxels away)");
                // Measured: 0 everywhere since cone levels are clamped by the height above the
                // receiver's plane (before: at 6 voxels 8.7 % / 2.4 % / 0.3 % for 6/16/32
                // cones, where the wide cones of the 6-set read the blocker at coarse levels,
                // partly averaged away). The bounds keep that margin for other layouts.
                CHECK(leak < (receiverX > 9.0f ? 0.01f : count == 6 ? 0.1f : 0.03f));
            }
        }
}

TEST_CASE("cone irradiance never exceeds pi times the brightest radiance", "[cone]") {
    // Composited radiance is a convex mix of sample colours c/α ≤ L_max times A ≤ 1.
    const float h = 0.05f;
    SceneBuilder builder(h);
    float brightest = 0.0f;
    for (int i = 0; i < 6000; ++i) {
        Pcg32 rng = Pcg32::forItem(uint64_t(i), 0, 99);
        const ivec3 c(int(rng.nextU32() % 24), int(rng.nextU32() % 24), int(rng.nextU32() % 24));
        VoxelSpec spec;
        spec.solid = rng.next1D() < 0.3f;
        spec.opacity = 0.05f + 0.95f * rng.next1D();
        spec.radiance = vec3(rng.next1D(), rng.next1D(), rng.next1D()) * 10.0f;
        brightest = glm::max(brightest, maxComponent(spec.radiance));
        builder.add(c, spec);
    }
    static const RadianceMips mips = buildRadianceMips(builder.build());
    const MipView view = mips.view();
    for (int count : {6, 16, 32}) {
        ConeSettings settings = settingsFor(count);
        for (int i = 0; i < 300; ++i) {
            Pcg32 rng = Pcg32::forItem(uint64_t(i), 1, 7);
            const vec3 p = vec3(rng.next1D(), rng.next1D(), rng.next1D()) * 24.0f * h;
            const float u1 = rng.next1D();
            const vec3 n = sampleUniformSphere(vec2(u1, rng.next1D()));
            settings.stepFactor = 0.1f + rng.next1D();
            settings.startOffset = 2.0f * rng.next1D();
            float occlusion = 0.0f;
            const vec3 e = coneTraceIrradiance(view, p, n, coneSet(count), settings, &occlusion);
            INFO("receiver " << i);
            CHECK(maxComponent(e) <= kPi * brightest * (1.0f + 1e-5f));
            CHECK(occlusion >= 0.0f);
            CHECK(occlusion <= 1.0f);
        }
    }
}

TEST_CASE("degenerate receivers give finite irradiance", "[cone]") {
    const float h = 0.1f;
    static const RadianceMips mips = buildRadianceMips(vl::test::closedBox(8, 1, vec3(1.0f), vec3(0.0f), h));
    const MipView view = mips.view();
    const ConeSet& set = coneSet(16);
    const ConeSettings settings;
    // Zero and NaN normals: no direction to gather from, so zero.
    CHECK(coneTraceIrradiance(view, vec3(0.3f), vec3(0.0f), set, settings) == vec3(0.0f));
    CHECK(coneTraceIrradiance(view, vec3(0.3f), vec3(std::nanf(""), 0, 1), set, settings) == vec3(0.0f));
    CHECK(coneTraceIrradiance(view, vec3(std::nanf(""), 0, 0), vec3(0, 0, 1), set, settings) == vec3(0.0f));
    // A receiver exactly on a voxel corner, along axes and diagonals.
    CHECK(coneTraceIrradiance(view, vec3(0.3f), vec3(0, 1e-30f, 0), set, settings) == vec3(0.0f));
    for (const vec3 n : {vec3(0, 0, 1), vec3(-1, 0, 0), glm::normalize(vec3(1, 1, 1)), vec3(0, 1e-3f, 0)}) {
        const vec3 e = coneTraceIrradiance(view, vec3(3.5f, 3.5f, 3.5f) * h, n, set, settings);
        CHECK(isFinite(e));
        CHECK(e.x > 0.0f);
    }
    // Outside the grid: finite; facing away, zero; far away, zero.
    CHECK(coneTraceIrradiance(view, vec3(-5.0f), vec3(-1, 0, 0), set, settings) == vec3(0.0f));
    CHECK(isFinite(coneTraceIrradiance(view, vec3(-5.0f), vec3(1, 1, 1), set, settings)));
    CHECK(coneTraceIrradiance(view, vec3(1e30f), vec3(0, 0, 1), set, settings) == vec3(0.0f));
    CHECK(isFinite(coneTraceIrradiance(view, vec3(-1e30f), vec3(1, 1, 1), set, settings)));
    // A nearly flat cone (89.9°) still terminates and stays finite.
    ConeSettings flat;
    flat.apertureDegrees = 89.9f;
    CHECK(isFinite(coneTraceIrradiance(view, vec3(0.35f), vec3(0, 0, 1), set, flat)));
}

TEST_CASE("cones from the dark side of a thin wall lit on the other side gather nothing from it", "[cone]") {
    // A solid double-sided wall one voxel thick (normal +X, equal ± weights) whose +X face
    // radiates L (lit from that side) and whose −X face is dark. Receivers on the −X side
    // facing it gather exactly 0 at every distance. With one isotropic radiance per voxel
    // (the wall voxel's mean, L) the same receivers see the lit side through the wall.
    const float h = 0.1f;
    const vec3 lit(1.0f, 0.5f, 0.25f);
    SceneBuilder builder(h);
    VoxelSpec wall;
    wall.normal = vec3(1, 0, 0);
    wall.axisWeights = {1, 1, 0, 0, 0, 0};
    wall.directional = true;
    wall.faces[0] = lit;
    wall.radiance = lit;  // faceWeightedMean: the lit side
    for (int y = -24; y <= 24; ++y)
        for (int z = -24; z <= 24; ++z) builder.add(ivec3(0, y, z), wall);
    VoxelScene scene = builder.build();
    const RadianceMips directional = buildRadianceMips(scene);
    scene.faceRadiance.clear();
    const RadianceMips isotropic = buildRadianceMips(scene);
    for (int count : {6, 16, 32})
        for (float distance : {1.5f, 3.0f, 8.0f})
            for (const vec3 n : {vec3(1, 0, 0), glm::normalize(vec3(1.0f, 0.4f, -0.3f))}) {
                const vec3 p = vec3(-distance, 0.3f, -0.2f) * h;
                float occlusion = 0.0f;
                const vec3 e = coneTraceIrradiance(directional.view(), p, n, coneSet(count), settingsFor(count), &occlusion);
                const vec3 leak = coneTraceIrradiance(isotropic.view(), p, n, coneSet(count), settingsFor(count));
                INFO(count << " cones, " << distance << " voxels before the wall: E = " << e.x << " (isotropic "
                           << leak.x << ", E/π = " << leak.x / kPi << " of L " << lit.x << "), occlusion " << occlusion);
                CHECK(e == vec3(0.0f));
                CHECK(occlusion > 0.5f);  // the wall is there and opaque
                CHECK(leak.x > 0.3f * kPi * lit.x);
            }
}

TEST_CASE("a voxel with a bright top face and a dark side face looks bright only from above", "[cone]") {
    // The edge voxel of a block: top face +Y radiates L, side face +X is dark. A narrow cone
    // from above sees L (times its opacity); one from the +X side sees it opaque and dark;
    // one at 45° between them sees both faces with equal coverage: L/2.
    const float h = 0.1f;
    const vec3 bright(2.0f, 1.0f, 0.5f);
    SceneBuilder builder(h);
    VoxelSpec edge;
    edge.normal = glm::normalize(vec3(1, 1, 0));
    edge.axisWeights = {1, 0, 1, 0, 0, 0};
    edge.directional = true;
    edge.faces[2] = bright;
    edge.radiance = 0.5f * bright;
    builder.add(ivec3(0), edge);
    const RadianceMips mips = buildRadianceMips(builder.build());
    const MipView view = mips.view();
    const auto look = [&](const vec3& from) {
        return traceCone(view, from * (12.0f * h), -glm::normalize(from), 0.01f, 0.5f, 0.0f);
    };
    const ConeResult above = look(vec3(0, 1, 0));
    CHECK(above.occlusion > 0.99f);
    CHECK(glm::distance(above.radiance, bright * above.occlusion) < 1e-5f);
    const ConeResult side = look(vec3(1, 0, 0));
    CHECK(side.occlusion > 0.99f);
    CHECK(side.radiance == vec3(0.0f));
    const ConeResult diagonal = look(glm::normalize(vec3(1, 1, 0)));
    CHECK(glm::distance(diagonal.radiance, 0.5f * bright * diagonal.occlusion) < 1e-5f);
    // From below (the −Y face has no surface and faces nothing bright): opaque and dark.
    const ConeResult below = look(vec3(0, -1, 0));
    CHECK(below.occlusion > 0.99f);
    CHECK(below.radiance == vec3(0.0f));
}
