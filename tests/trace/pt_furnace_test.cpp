// White furnace and Russian roulette: inside a closed sphere of albedo ρ and emitted
// radiance Le every path sees L = Le Σ_k ρ^k, so each pixel must match the geometric sum
// within its own Monte Carlo error bound, and cutting the sum by max bounces or splitting it
// into direct and indirect parts must give the partial sums.
#include "pt_scenes.h"

#include "core/error.h"
#include "trace/camera.h"
#include "trace/path_tracer.h"

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>

using namespace vl;
using namespace vl::test;

namespace {

const vec3 kAlbedo(0.2f, 0.5f, 0.8f);
const vec3 kLe(1.0f, 2.0f, 0.5f);

TraceFixture furnace() {
    Scene scene;
    scene.sourcePath = "furnace";
    scene.materials.push_back(lambert("wall", kAlbedo, kLe));
    scene.meshes.push_back(makeIcosphere("sphere", vec3(0.3f, -0.2f, 0.1f), 2.0f, 2, 0));
    return TraceFixture(std::move(scene));
}

CameraModel insideCamera(int size) {
    Camera c;
    c.position = vec3(0.3f, -0.2f, 0.1f);
    c.forward = glm::normalize(vec3(0.2f, 0.1f, -1.0f));
    c.up = glm::normalize(glm::cross(glm::cross(c.forward, vec3(0, 1, 0)), c.forward));
    c.yfov = 1.2f;
    return makeCameraModel(c, size, size);
}

// Le Σ_{k=0}^{n-1} ρ^k per channel.
vec3 partialSum(int terms) {
    vec3 out;
    for (int c = 0; c < 3; ++c) out[c] = kLe[c] * (1.0f - std::pow(kAlbedo[c], float(terms))) / (1.0f - kAlbedo[c]);
    return out;
}

struct ImageMean {
    vec3 mean{0.0f};
    vec3 sigma{0.0f};  // standard error of the mean over all pixels
};

ImageMean imageMean(const TraceResult& r) {
    ImageMean m;
    glm::dvec3 sum(0.0), var(0.0);
    const size_t n = static_cast<size_t>(r.beauty.width) * r.beauty.height;
    for (int y = 0; y < r.beauty.height; ++y)
        for (int x = 0; x < r.beauty.width; ++x) {
            sum += glm::dvec3(r.beauty.rgb(x, y));
            var += glm::dvec3(r.variance.rgb(x, y));
        }
    m.mean = vec3(sum / double(n));
    m.sigma = vec3(glm::sqrt(var) / double(n));
    return m;
}

}  // namespace

TEST_CASE("White furnace: every pixel is Le over one minus albedo within its Monte Carlo error", "[trace]") {
    TraceFixture f = furnace();
    PathTracerSettings settings;
    settings.samplesPerPixel = 64;
    settings.quiet = true;
    const TraceResult r = renderCamera(f.trace, f.bvh, insideCamera(16), settings);
    REQUIRE(r.nonFiniteSamples == 0);
    const vec3 expected = partialSum(settings.path.maxBounces + 2);  // ρ^66 is below float precision
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) {
                const float sigma = std::sqrt(r.variance.at(x, y, c));
                INFO("pixel " << x << ", " << y << " channel " << c << " sigma " << sigma);
                REQUIRE(sigma > 0.0f);
                // 5σ per pixel: a false alarm among 768 values has probability ~4e-4.
                REQUIRE(std::abs(r.beauty.at(x, y, c) - expected[c]) <= 5.0f * sigma + 1e-5f * expected[c]);
            }
    const ImageMean m = imageMean(r);
    for (int c = 0; c < 3; ++c) {
        INFO("channel " << c << " mean " << m.mean[c] << " expected " << expected[c] << " sigma " << m.sigma[c]);
        REQUIRE(std::abs(m.mean[c] - expected[c]) <= 4.0f * m.sigma[c]);
        // The bound is tight enough to mean something: under 1% of the value.
        REQUIRE(m.sigma[c] < 0.01f * expected[c]);
    }
}

TEST_CASE("Max bounces truncates the series and direct plus indirect splits it after one scattering", "[trace]") {
    TraceFixture f = furnace();
    PathTracerSettings settings;
    settings.samplesPerPixel = 32;
    settings.quiet = true;
    for (int bounces : {0, 2}) {
        settings.path.maxBounces = bounces;
        const TraceResult r = renderCamera(f.trace, f.bvh, insideCamera(16), settings);
        const ImageMean m = imageMean(r);
        // Light scattered at most B + 1 times: Le (1 + ρ + … + ρ^(B+1)).
        const vec3 expected = partialSum(bounces + 2);
        glm::dvec3 direct(0.0), indirect(0.0);
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x) {
                direct += glm::dvec3(r.direct.rgb(x, y));
                indirect += glm::dvec3(r.indirect.rgb(x, y));
            }
        direct /= 256.0;
        indirect /= 256.0;
        for (int c = 0; c < 3; ++c) {
            INFO("bounces " << bounces << " channel " << c);
            REQUIRE(std::abs(m.mean[c] - expected[c]) <= 4.0f * m.sigma[c]);
            // Direct holds Le + ρ Le (emission seen, and scattered once); indirect the rest.
            const float directExpected = partialSum(2)[c];
            REQUIRE(std::abs(float(direct[c]) - directExpected) <= 4.0f * m.sigma[c]);
            if (bounces == 0) REQUIRE(indirect[c] == 0.0);
            else REQUIRE(std::abs(float(indirect[c]) - (expected[c] - directExpected)) <= 4.0f * m.sigma[c]);
        }
    }
}

TEST_CASE("Russian roulette is unbiased: the mean with it equals the mean without within 3 sigma", "[trace]") {
    TraceFixture f = furnace();
    PathTracerSettings with;
    with.samplesPerPixel = 64;
    with.quiet = true;
    with.path.rouletteStart = 1;  // act early and often, so a bias would show
    with.path.maxBounces = 24;    // the same truncation for both; keeps the run without roulette short
    PathTracerSettings without = with;
    without.path.russianRoulette = false;
    without.seed = 12345;  // independent samples: the 3σ bound below assumes it
    const ImageMean a = imageMean(renderCamera(f.trace, f.bvh, insideCamera(16), with));
    const ImageMean b = imageMean(renderCamera(f.trace, f.bvh, insideCamera(16), without));
    for (int c = 0; c < 3; ++c) {
        const float sigma = std::sqrt(a.sigma[c] * a.sigma[c] + b.sigma[c] * b.sigma[c]);
        INFO("channel " << c << " with " << a.mean[c] << " without " << b.mean[c] << " sigma " << sigma);
        REQUIRE(std::abs(a.mean[c] - b.mean[c]) <= 3.0f * sigma);
    }
    // Roulette ends paths early, so it pays in variance where the throughput is low (red).
    REQUIRE(a.sigma.x > b.sigma.x);
}

TEST_CASE("Renders are the same bytes on one thread and on many", "[trace]") {
    TraceFixture f = furnace();
    PathTracerSettings settings;
    settings.samplesPerPixel = 4;
    settings.quiet = true;
    TraceResult one, many;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = renderCamera(f.trace, f.bvh, insideCamera(24), settings);
    }
    many = renderCamera(f.trace, f.bvh, insideCamera(24), settings);
    REQUIRE(one.beauty.pixels.size() == many.beauty.pixels.size());
    REQUIRE(std::memcmp(one.beauty.pixels.data(), many.beauty.pixels.data(), one.beauty.pixels.size() * 4) == 0);
    REQUIRE(std::memcmp(one.indirect.pixels.data(), many.indirect.pixels.data(), one.indirect.pixels.size() * 4) == 0);
}

TEST_CASE("Path tracer settings out of range are rejected before any work", "[trace]") {
    TraceFixture f = furnace();
    PathTracerSettings settings;
    settings.samplesPerPixel = 0;
    REQUIRE_THROWS_AS(renderCamera(f.trace, f.bvh, insideCamera(4), settings), SettingsError);
    settings.samplesPerPixel = 1;
    settings.path.maxBounces = -1;
    REQUIRE_THROWS_AS(renderCamera(f.trace, f.bvh, insideCamera(4), settings), SettingsError);
}
