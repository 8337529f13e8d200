// The receivers' exact direct term (lighting/direct_light.h) against closed forms: a square light
// over a floor, a ledge half way up casting a penumbra across it.
#include "lighting/direct_light.h"
#include "scene/scene.h"
#include "support/form_factor.h"
#include "tests/bake/quad_scene.h"
#include "core/rng.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;
using namespace vl::test;

namespace {

// A floor at z = 0 and a ledge at z = 0.5 over x < 0 (albedo 0.5); returns the material of
// radiance Le for the light the test adds above them.
int addFloorAndLedge(Scene& scene, float Le) {
    const int floor = addLambert(scene, vec3(0.5f));
    const int light = addLambert(scene, vec3(0.0f), vec3(Le));
    addQuad(scene, "floor", floor, vec3(-2, -2, 0), vec3(2, -2, 0), vec3(2, 2, 0), vec3(-2, 2, 0));
    addQuad(scene, "ledge", floor, vec3(-2, -2, 0.5f), vec3(0, -2, 0.5f), vec3(0, 2, 0.5f), vec3(-2, 2, 0.5f));
    return light;
}

}  // namespace

TEST_CASE("A quad light's penumbra at the receivers: one square grid over the quad errs less than its two triangles",
          "[bake]") {
    // Light: the square [−0.3, 0.3]² at z = 1 facing down, radiance 2. Ledge: z = 0.5 over
    // x < 0. A floor point p (z = 0) sees the part of the light with x ≥ −p.x (the ray to it
    // crosses z = 0.5 at (p.x + x) / 2), so its irradiance is Le·π·F of that rectangle.
    const float Le = 2.0f, half = 0.3f;
    Scene scene;
    const int light = addFloorAndLedge(scene, Le);
    addQuad(scene, "light", light, vec3(-half, -half, 1), vec3(-half, half, 1), vec3(half, half, 1),
            vec3(half, -half, 1));
    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    const TraceScene trace = TraceScene::build(scene, triangles);
    REQUIRE(trace.emitterQuad == std::vector<int8_t>{kQuadFirstHalf, kQuadSecondHalf});
    TraceSceneView asQuad = trace.view();
    TraceSceneView asTriangles = asQuad;
    asTriangles.emitterQuad = nullptr;

    DirectLightSettings settings;
    settings.emitterStrata = 4;  // 4 × 4 a triangle: 32 points; the quad ⌈4√2⌉² = 36
    double squaresQuad = 0.0, squaresTriangles = 0.0, worstLit = 0.0;
    int penumbra = 0;
    for (int i = 0; i < 400; ++i) {
        SurfaceSample r;
        r.position = vec3(-0.35f + 0.7f * (i + 0.5f) / 400.0f, 0.37f * std::sin(0.1f * float(i)), 0.0f);
        r.normal = vec3(0, 0, 1);
        r.triangle = 0;
        const double x = r.position.x, y = r.position.y;
        const double all = Le * M_PI * rectangleFormFactor(-half - x, half - x, -half - y, half - y, 1.0);
        const double exact =
            Le * M_PI * rectangleFormFactor(std::max(-double(half), -x) - x, half - x, -half - y, half - y, 1.0);
        const double quad = directIrradiance(asQuad, bvh.view(), r, settings, uint64_t(i)).x;
        const double halves = directIrradiance(asTriangles, bvh.view(), r, settings, uint64_t(i)).x;
        if (x >= half + 0.01) {  // the whole light in view: exact up to rounding
            worstLit = std::max(worstLit, std::abs(quad - exact) / exact);
        } else if (exact > 0.0 && exact < all) {  // errors as shares of the unshadowed light
            squaresQuad += (quad - exact) * (quad - exact) / (all * all);
            squaresTriangles += (halves - exact) * (halves - exact) / (all * all);
            ++penumbra;
        }
    }
    const double quadError = std::sqrt(squaresQuad / penumbra), trianglesError = std::sqrt(squaresTriangles / penumbra);
    INFO(penumbra << " receivers in the penumbra: RMS error " << quadError << " of the unshadowed light as one quad, "
                  << trianglesError << " as two triangles; wholly lit ones within " << worstLit);
    REQUIRE(penumbra > 100);
    CHECK(quadError < 0.85 * trianglesError);
    CHECK(quadError < 0.03);
    CHECK(worstLit < 1e-4);
}

TEST_CASE("Many emissive triangles are sampled by their tree at the receivers, and agree with the exact light", "[bake]") {
    // The light above, tessellated into 10 × 10 squares (200 triangles, past kLightTreeFrom):
    // each receiver takes a cut of their tree (trace/light_tree.h) instead of visiting every
    // square. The estimate is unbiased: over 400 floor points, lit, in the ledge's penumbra
    // and in its shadow, its mean error is within 1% of the unshadowed light, and each point
    // within a few percent of the exact form factor.
    const float Le = 2.0f, half = 0.3f;
    Scene scene;
    const int light = addFloorAndLedge(scene, Le);
    constexpr int kTiles = 10;
    const float step = 2.0f * half / kTiles;
    for (int a = 0; a < kTiles; ++a)
        for (int b = 0; b < kTiles; ++b) {
            const float x = -half + a * step, y = -half + b * step;
            addQuad(scene, "light", light, vec3(x, y, 1), vec3(x, y + step, 1), vec3(x + step, y + step, 1),
                    vec3(x + step, y, 1));
        }
    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    const TraceScene trace = TraceScene::build(scene, triangles);
    REQUIRE(trace.emitters.size() == 2 * kTiles * kTiles);
    REQUIRE(trace.emitters.size() > kLightTreeFrom);
    REQUIRE(trace.emitterTree.size() == 2 * kTiles * kTiles - 1);

    const DirectLightSettings settings;
    double signedSum = 0.0, squares = 0.0;
    const int n = 400;
    for (int i = 0; i < n; ++i) {
        SurfaceSample r;
        r.position = vec3(-0.6f + 1.2f * (i + 0.5f) / n, 0.37f * std::sin(0.1f * float(i)), 0.0f);
        r.normal = vec3(0, 0, 1);
        r.triangle = 0;
        const double x = r.position.x, y = r.position.y;
        const double all = Le * M_PI * rectangleFormFactor(-half - x, half - x, -half - y, half - y, 1.0);
        const double from = std::max(-double(half), -x);
        const double exact = from < half ? Le * M_PI * rectangleFormFactor(from - x, half - x, -half - y, half - y, 1.0) : 0.0;
        const double sampled = directIrradiance(trace.view(), bvh.view(), r, settings, uint64_t(i)).x;
        signedSum += (sampled - exact) / all;
        squares += (sampled - exact) * (sampled - exact) / (all * all);
    }
    const double bias = signedSum / n, rms = std::sqrt(squares / n);
    INFO("mean error " << bias << ", RMS error " << rms << " of the unshadowed light");
    CHECK(std::abs(bias) < 0.01);
    CHECK(rms < 0.05);
}

TEST_CASE("Many lights by their trees at the receivers and the voxels' points agree with every light visited", "[bake]") {
    // The floor and ledge above under 150 point lights and 100 emissive panels (a 10 × 10 grid
    // of quads at z = 1.2 facing down), both past kLightTreeFrom: each receiver takes a cut of
    // each tree (light_tree.h) instead of visiting all. Over 400 floor points, lit, in the
    // ledge's shadows and under it, the trees' light agrees with the exact sums of the same
    // scene built without trees (many-lights each): the mean within 1% (it is unbiased; the
    // points' own noise averages out), each point within the cut's noise (light-cut 64). The voxels'
    // surface points (surfacePointIrradiance, a cut of 4) likewise, over 16 points u each.
    Scene scene;
    const int light = addFloorAndLedge(scene, 1.5f);
    Pcg32 rng(23, 4);
    for (int i = 0; i < 150; ++i) {
        float x, y, z, w;
        rng.next2D(x, y);
        rng.next2D(z, w);
        Light lamp = pointLightAt(vec3(4.0f * x - 2.0f, 4.0f * y - 2.0f, 0.6f + 1.4f * z), 0.02f + 0.2f * w);
        scene.lights.push_back(lamp);
    }
    for (int a = 0; a < 10; ++a)
        for (int b = 0; b < 10; ++b) {
            const float x = -1.5f + 0.3f * a, y = -1.5f + 0.3f * b;
            addQuad(scene, "panel", light, vec3(x, y, 1.2f), vec3(x, y + 0.2f, 1.2f), vec3(x + 0.2f, y + 0.2f, 1.2f),
                    vec3(x + 0.2f, y, 1.2f));
        }
    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    const TraceScene withTrees = TraceScene::build(scene, triangles);
    const TraceScene visiting = TraceScene::build(scene, triangles, false);
    REQUIRE(!withTrees.pointLightTree.empty());
    REQUIRE(!withTrees.emitterTree.empty());
    REQUIRE(visiting.pointLightTree.empty());
    REQUIRE(visiting.emitterTree.empty());

    const DirectLightSettings settings;
    double signedSum = 0.0, squares = 0.0, exactSum = 0.0, pointSigned = 0.0, pointSquares = 0.0;
    const int n = 400;
    for (int i = 0; i < n; ++i) {
        SurfaceSample r;
        r.position = vec3(-1.8f + 3.6f * (i + 0.5f) / n, 1.7f * std::sin(0.37f * float(i)), 0.0f);
        r.normal = vec3(0, 0, 1);
        r.triangle = 0;
        const double exact = directIrradiance(visiting.view(), bvh.view(), r, settings, uint64_t(i)).x;
        const double tree = directIrradiance(withTrees.view(), bvh.view(), r, settings, uint64_t(i)).x;
        signedSum += tree - exact;
        squares += (tree - exact) * (tree - exact);
        exactSum += exact;
        double pointExact = 0.0, pointTree = 0.0;
        for (int k = 0; k < 16; ++k) {
            const vec2 u((k % 4 + 0.5f) / 4.0f, (k / 4 + 0.5f) / 4.0f);
            const vec3 ng(0, 0, 1);
            pointExact += surfacePointIrradiance(visiting.view(), bvh.view(), r.position, ng, ng, u, 0.0f, uint64_t(i)).x;
            pointTree += surfacePointIrradiance(withTrees.view(), bvh.view(), r.position, ng, ng, u, 0.0f,
                                                uint64_t(16 * i + k))
                             .x;
        }
        pointSigned += (pointTree - pointExact) / 16.0;
        pointSquares += (pointTree - pointExact) * (pointTree - pointExact) / 256.0;
    }
    const double mean = exactSum / n;
    const double bias = signedSum / n / mean, rms = std::sqrt(squares / n) / mean;
    const double pointBias = pointSigned / n / mean, pointRms = std::sqrt(pointSquares / n) / mean;
    INFO("receivers: mean error " << bias << ", RMS " << rms << " of the mean light; surface points (16 each): mean "
                                  << pointBias << ", RMS " << pointRms);
    // The RMS bounds are the cuts' noise (64 nodes at a receiver, 4 at a surface point over 16
    // points), most of it in the ledge's partial shadow, which no unshadowed bound foresees;
    // docs/many-lights.md gives what they measure.
    CHECK(std::abs(bias) < 0.01);
    CHECK(rms < 0.05);
    CHECK(std::abs(pointBias) < 0.01);
    CHECK(pointRms < 0.12);
}
