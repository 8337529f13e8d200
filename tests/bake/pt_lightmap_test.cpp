// The reference path tracer on lightmap receivers: exact direct light from a point light
// through the whole chain (rasterised probes, spp shared among them), and the Cornell atlases
// against Cycles' DIFFUSE bakes in ../shared/reference (E/π per texel, covered texels only).
//
// Cornell tolerances (S = spp of the test bake):
// - per-channel mean over covered texels: 1% (the bound for systematic differences)
//   + 4σ of the mean, σ from the bake's own per-texel sample variance;
// - relative RMSE, area light: Cycles' own 256² bake shows 17.6% at 16 spp against its
//   reference (README table, which also gives 8.3% at 64, 4.0% at 256: ∝ 1/√spp), so at S
//   spp Cycles would show 17.6% · √(16 / S); we allow the factor 1.5;
// - relative RMSE, point light (no Cycles table): 1.5× the error our own sample variance
//   predicts, the reference's noise estimated as ours at its 4096 spp.
#include "receivers/receivers.h"

#include "core/image_io.h"
#include "metrics/metrics.h"
#include "scene/gltf_loader.h"
#include "support/cycles_comparison.h"
#include "support/paths.h"
#include "trace/bvh.h"
#include "trace/path_tracer.h"
#include "trace/trace_scene.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;

TEST_CASE("Point light over a rasterised plane: each texel is the mean of I cos theta over pi r squared at its probes", "[bake]") {
    Scene scene;
    scene.sourcePath = "plane";
    Material grey;
    grey.name = "grey";
    grey.baseColorFactor = vec4(0.5f, 0.5f, 0.5f, 1.0f);
    scene.materials.push_back(grey);
    Mesh plane;
    plane.name = "plane";
    plane.material = 0;
    plane.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
    plane.normals.assign(4, vec3(0, 1, 0));
    plane.uv1 = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    plane.indices = {0, 2, 1, 0, 3, 2};
    scene.meshes.push_back(plane);
    Light light;
    light.position = vec3(0.2f, 0.3f, -0.1f);  // close: the field varies strongly within a texel
    light.intensity = 1.5f;
    scene.lights.push_back(light);

    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    const TraceScene trace = TraceScene::build(scene, triangles);
    LightmapSettings lightmap;
    lightmap.width = lightmap.height = 16;
    lightmap.subsamplesPerAxis = 4;
    lightmap.samplePerTriangle = false;
    Diagnostics diagnostics(false, false);
    const LightmapAtlas atlas = buildLightmapReceivers(scene, lightmap, diagnostics).at(0);
    PathTracerSettings settings;
    settings.samplesPerPixel = 16;  // one path per probe
    settings.quiet = true;
    const TraceResult r = traceIrradiance(trace, bvh, atlas.receivers, settings);

    auto eOverPi = [&](vec3 p) {
        const vec3 d = light.position - p;
        const double r2 = glm::dot(d, d);
        return light.intensity * (d.y / std::sqrt(r2)) / (M_PI * r2);
    };
    double maxSpread = 0.0;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            double expected = 0.0, lo = 1e30, hi = 0.0;
            for (int j = 0; j < 4; ++j)
                for (int i = 0; i < 4; ++i) {
                    const vec3 p(-1.0f + 2.0f * (x + (i + 0.5f) / 4.0f) / 16.0f, 0.0f,
                                 -1.0f + 2.0f * (y + (j + 0.5f) / 4.0f) / 16.0f);
                    const double e = eOverPi(p);
                    expected += e / 16.0;
                    lo = std::min(lo, e);
                    hi = std::max(hi, e);
                }
            maxSpread = std::max(maxSpread, (hi - lo) / expected);
            INFO("texel " << x << ", " << y);
            REQUIRE(r.direct.at(x, y, 0) == Approx(expected).epsilon(1e-3));
            REQUIRE(r.indirect.at(x, y, 0) == 0.0f);
            REQUIRE(r.variance.at(x, y, 0) >= 0.0f);
        }
    // Probes matter: within some texel the irradiance varies far more than the tolerance.
    REQUIRE(maxSpread > 0.1);
}

namespace {

struct LightmapComparison {
    ErrorMetrics total;
    ErrorMetrics direct;
    double sigmaMean[3];
    double expectedRelRmse;
};

constexpr int kSpp = 16;

LightmapComparison bakeAndCompare(const std::string& name) {
    const std::string dir = vl::test::sharedDir() + "/reference/";
    LoadOptions load;
    load.echoWarnings = false;
    const Scene scene = loadGltf(dir + name + ".gltf", load);
    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    const TraceScene trace = TraceScene::build(scene, triangles);
    Diagnostics diagnostics(false, false);
    const LightmapAtlas atlas = buildLightmapReceivers(scene, LightmapSettings{}, diagnostics).at(0);
    PathTracerSettings settings;
    settings.samplesPerPixel = kSpp;
    settings.quiet = true;
    const TraceResult r = traceIrradiance(trace, bvh, atlas.receivers, settings);
    REQUIRE(r.nonFiniteSamples == 0);

    const Image mask = readImage(dir + "cycles/" + name + "_lightmap_mask.exr");
    MetricOptions options;
    options.mask = &mask;
    options.testName = name + " lightmap";
    options.referenceName = "Cycles 4096 spp";
    LightmapComparison out;
    out.total = compareImages(r.beauty, readImage(dir + "cycles/" + name + "_lightmap_4096spp.exr"), options);
    out.direct = compareImages(r.direct, readImage(dir + "cycles/" + name + "_lightmap_direct_4096spp.exr"), options);
    double varSum[3] = {0, 0, 0}, varAll = 0.0;
    for (int y = 0; y < mask.height; ++y)
        for (int x = 0; x < mask.width; ++x) {
            if (!(mask.at(x, y, 0) > 0.5f)) continue;
            REQUIRE(atlas.mask.at(x, y) == 1.0f);  // every texel Cycles bakes, we bake
            for (int c = 0; c < 3; ++c) {
                varSum[c] += r.variance.at(x, y, c);
                varAll += r.variance.at(x, y, c);
            }
        }
    const double n = static_cast<double>(out.total.pixels);
    double meanAll = 0.0;
    for (int c = 0; c < 3; ++c) {
        out.sigmaMean[c] = std::sqrt(varSum[c]) / n;
        meanAll += out.total.meanReference[c] / 3.0;
    }
    out.expectedRelRmse = std::sqrt(varAll / (3 * n)) / meanAll;
    return out;
}

void requireMeansAgree(const LightmapComparison& c) { test::requireMeansAgree(c.total, c.sigmaMean); }

}  // namespace

TEST_CASE("Cornell box with an area light: the lightmap matches the Cycles bake", "[bake]") {
    VL_SKIP_WITHOUT_SHARED();
    const LightmapComparison c = bakeAndCompare("cornell_quad");
    requireMeansAgree(c);
    const double cyclesAtThisSpp = 0.176 * std::sqrt(16.0 / kSpp);
    INFO("relative RMSE " << c.total.relativeRmse << ", Cycles would show " << cyclesAtThisSpp);
    REQUIRE(c.total.relativeRmse <= 1.5 * cyclesAtThisSpp);
}

TEST_CASE("Cornell box with a point light: the lightmap matches the Cycles bake", "[bake]") {
    VL_SKIP_WITHOUT_SHARED();
    const LightmapComparison c = bakeAndCompare("cornell_point");
    requireMeansAgree(c);
    const double bound = 1.5 * c.expectedRelRmse * std::sqrt(1.0 + kSpp / 4096.0);
    INFO("relative RMSE " << c.total.relativeRmse << ", expected from our variance " << c.expectedRelRmse);
    REQUIRE(c.total.relativeRmse <= bound);
    // A point light's direct part has no noise here: its mean is the reference's to 1%.
    for (int ch = 0; ch < 3; ++ch)
        REQUIRE(c.direct.meanTest[ch] == Approx(c.direct.meanReference[ch]).epsilon(0.01));
}
