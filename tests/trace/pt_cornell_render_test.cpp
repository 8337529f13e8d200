// Against an independent renderer: Cycles' 4096-spp renders of the two Cornell boxes in
// ../shared/reference (see its README). A 128 × 128 render with a box pixel filter is, in
// expectation, the 2 × 2 box average of the 256 × 256 reference, so the test compares with
// that average; pixels that hold any reference pixel above 5 (the emitter) are excluded, as
// the README does.
//
// Tolerances (S = spp of the test render):
// - per-channel mean: 1% (the bound for systematic differences) + 4σ of the mean,
//   σ from the render's own per-pixel sample variance;
// - relative RMSE: Cycles' own table gives 11.2% for a 256² render at 64 spp against the
//   reference, ∝ 1/√spp. A pixel's relative noise depends on its sample count, not its
//   size (a 128² pixel's per-sample spread is about that of a 256² one), so at S spp Cycles
//   would show 11.2% · √(64 / S), its reference's own noise included; we allow the issue's
//   factor 1.5 on that. For the point-light scene the README has no table: the bound is
//   1.5× the error expected from our own sample variance, with the reference's noise
//   estimated as ours at its 4 · 4096 samples per 128² pixel.
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

namespace {

constexpr int kRes = 128;
constexpr int kFactor = 2;  // 256 / 128
constexpr int kSpp = 64;

Image boxDownsample(const Image& image, int factor) {
    Image out(image.width / factor, image.height / factor, 3);
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x)
            for (int c = 0; c < 3; ++c) {
                double sum = 0.0;
                for (int j = 0; j < factor; ++j)
                    for (int i = 0; i < factor; ++i) sum += image.at(x * factor + i, y * factor + j, c);
                out.at(x, y, c) = static_cast<float>(sum / (factor * factor));
            }
    return out;
}

// 1 where no reference pixel under the coarse pixel exceeds 5.
Image emitterFreeMask(const Image& reference, int factor) {
    Image mask(reference.width / factor, reference.height / factor, 1, 1.0f);
    for (int y = 0; y < reference.height; ++y)
        for (int x = 0; x < reference.width; ++x)
            for (int c = 0; c < 3; ++c)
                if (reference.at(x, y, c) > 5.0f) mask.at(x / factor, y / factor) = 0.0f;
    return mask;
}

struct Comparison {
    ErrorMetrics metrics;
    double sigmaMean[3];
    double expectedRelRmse;  // from our sample variance alone
};

Comparison renderAndCompare(const std::string& name) {
    const std::string dir = vl::test::sharedDir() + "/reference/";
    LoadOptions load;
    load.echoWarnings = false;
    const Scene scene = loadGltf(dir + name + ".gltf", load);
    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    const TraceScene trace = TraceScene::build(scene, triangles);
    REQUIRE(scene.cameras.size() == 1);
    PathTracerSettings settings;
    settings.samplesPerPixel = kSpp;
    settings.filter = PixelFilter::Box;  // Cycles' 1-pixel box filter
    settings.quiet = true;
    const TraceResult r = renderCamera(trace, bvh, makeCameraModel(scene.cameras[0], kRes, kRes), settings);
    REQUIRE(r.nonFiniteSamples == 0);

    const Image full = readImage(dir + "cycles/" + name + "_render_4096spp.exr");
    REQUIRE(full.width == kRes * kFactor);
    const Image reference = boxDownsample(full, kFactor);
    const Image mask = emitterFreeMask(full, kFactor);
    MetricOptions options;
    options.mask = &mask;
    options.testName = name + " render";
    options.referenceName = "Cycles 4096 spp";
    Comparison out;
    out.metrics = compareImages(r.beauty, reference, options);
    double varSum[3] = {0, 0, 0}, varAll = 0.0, meanAll = 0.0;
    for (int y = 0; y < kRes; ++y)
        for (int x = 0; x < kRes; ++x) {
            if (!(mask.at(x, y) > 0.5f)) continue;
            for (int c = 0; c < 3; ++c) {
                varSum[c] += r.variance.at(x, y, c);
                varAll += r.variance.at(x, y, c);
                meanAll += reference.at(x, y, c);
            }
        }
    const double n = static_cast<double>(out.metrics.pixels);
    for (int c = 0; c < 3; ++c) out.sigmaMean[c] = std::sqrt(varSum[c]) / n;
    out.expectedRelRmse = std::sqrt(varAll / (3 * n)) / (meanAll / (3 * n));
    return out;
}

void requireMeansAgree(const Comparison& c) { test::requireMeansAgree(c.metrics, c.sigmaMean); }

}  // namespace

TEST_CASE("Cornell box with an area light matches the Cycles render", "[trace]") {
    VL_SKIP_WITHOUT_SHARED();
    const Comparison c = renderAndCompare("cornell_quad");
    requireMeansAgree(c);
    const double cyclesAtThisSpp = 0.112 * std::sqrt(64.0 / kSpp);
    INFO("relative RMSE " << c.metrics.relativeRmse << ", Cycles would show " << cyclesAtThisSpp);
    REQUIRE(c.metrics.relativeRmse <= 1.5 * cyclesAtThisSpp);
}

TEST_CASE("Cornell box with a point light matches the Cycles render", "[trace]") {
    VL_SKIP_WITHOUT_SHARED();
    const Comparison c = renderAndCompare("cornell_point");
    requireMeansAgree(c);
    const double referenceShare = static_cast<double>(kSpp) / (kFactor * kFactor * 4096.0);
    const double bound = 1.5 * c.expectedRelRmse * std::sqrt(1.0 + referenceShare);
    INFO("relative RMSE " << c.metrics.relativeRmse << ", expected from our variance " << c.expectedRelRmse);
    REQUIRE(c.metrics.relativeRmse <= bound);
}
