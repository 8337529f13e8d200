#include "core/error.h"
#include "metrics/metrics.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

using namespace vl;

namespace {

Image rgb(int w, int h, std::initializer_list<float> values) {
    Image image(w, h, 3);
    size_t i = 0;
    for (float v : values) image.pixels[i++] = v;
    return image;
}

}  // namespace

TEST_CASE("Metrics of identical images are zero", "[metrics]") {
    const Image a = rgb(2, 1, {0.5f, 1.0f, 2.0f, 3.0f, 0.0f, 0.25f});
    const ErrorMetrics m = compareImages(a, a);
    REQUIRE(m.pixels == 2);
    REQUIRE(m.rmse == 0.0);
    REQUIRE(m.relativeRmse == 0.0);
    REQUIRE(m.relMse == 0.0);
    REQUIRE(m.smape == 0.0);
    REQUIRE(m.meanTest[0] == Approx(1.75));
    REQUIRE(m.meanReference[2] == Approx(1.125));
}

TEST_CASE("Metrics match hand-computed values on a two-pixel image", "[metrics]") {
    // Differences per term: 0, 1, 2, -1, -1, -1; reference all ones.
    const Image test = rgb(2, 1, {1, 2, 3, 0, 0, 0});
    const Image ref = rgb(2, 1, {1, 1, 1, 1, 1, 1});
    const ErrorMetrics m = compareImages(test, ref);
    REQUIRE(m.rmse == Approx(std::sqrt(8.0 / 6.0)));
    REQUIRE(m.relativeRmse == Approx(std::sqrt(8.0 / 6.0)));  // mean reference is 1
    REQUIRE(m.relMse == Approx(8.0 / 1.01 / 6.0));
    const double smapeSum = 0.0 + 1.0 / 3.01 + 2.0 / 4.01 + 3.0 * (1.0 / 1.01);
    REQUIRE(m.smape == Approx(smapeSum / 6.0));
    REQUIRE(m.meanTest[0] == Approx(0.5));
    REQUIRE(m.meanTest[2] == Approx(1.5));

    // Relative RMSE divides by the pooled reference mean: doubling the reference scale
    // (and the test with it) leaves it unchanged, while RMSE doubles.
    Image test2 = test, ref2 = ref;
    for (float& v : test2.pixels) v *= 2.0f;
    for (float& v : ref2.pixels) v *= 2.0f;
    const ErrorMetrics m2 = compareImages(test2, ref2);
    REQUIRE(m2.rmse == Approx(2.0 * m.rmse));
    REQUIRE(m2.relativeRmse == Approx(m.relativeRmse));
}

TEST_CASE("Masked pixels are ignored by every metric", "[metrics]") {
    Image test = rgb(2, 1, {1, 2, 3, 1e6f, -1e6f, 1e6f});
    const Image ref = rgb(2, 1, {1, 1, 1, 1, 1, 1});
    Image mask(2, 1, 1);
    mask.at(0, 0) = 1.0f;
    MetricOptions options;
    options.mask = &mask;
    const ErrorMetrics m = compareImages(test, ref, options);
    REQUIRE(m.pixels == 1);
    REQUIRE(m.rmse == Approx(std::sqrt(5.0 / 3.0)));
    REQUIRE(m.relMse == Approx(5.0 / 1.01 / 3.0));
    REQUIRE(m.meanTest[1] == Approx(2.0));

    // The render convention: pixels whose reference exceeds 5 (the emitter) are dropped.
    const Image refBright = rgb(2, 1, {1, 1, 1, 17, 17, 17});
    MetricOptions bright;
    bright.excludeReferenceAbove = 5.0f;
    const ErrorMetrics mb = compareImages(test, refBright, bright);
    REQUIRE(mb.pixels == 1);
    REQUIRE(mb.rmse == Approx(std::sqrt(5.0 / 3.0)));
}

TEST_CASE("Metrics reject NaN input, size mismatches and empty masks", "[metrics]") {
    Image test = rgb(2, 1, {1, 2, 3, 0, 0, 0});
    const Image ref = rgb(2, 1, {1, 1, 1, 1, 1, 1});
    test.at(1, 0, 1) = std::numeric_limits<float>::quiet_NaN();
    try {
        compareImages(test, ref);
        FAIL("NaN input was accepted");
    } catch (const InputError& e) {
        const std::string message = e.what();
        REQUIRE(message.find("test") != std::string::npos);
        REQUIRE(message.find("pixel (1, 0) channel 1") != std::string::npos);
    }
    Image infRef = ref;
    infRef.at(0, 0, 0) = std::numeric_limits<float>::infinity();
    REQUIRE_THROWS_AS(compareImages(ref, infRef), InputError);
    REQUIRE_THROWS_AS(compareImages(Image(2, 2, 3), Image(2, 1, 3)), InputError);
    Image none(2, 1, 1, 0.0f);
    MetricOptions options;
    options.mask = &none;
    REQUIRE_THROWS_AS(compareImages(ref, ref, options), InputError);
    REQUIRE_THROWS_AS(relativeRmse(ref, Image(2, 1, 3, 0.0f)), InputError);
}
