// RGBM (export/lightmap_encoding.h): what a lightmap keeps through an 8-bit PNG.
#include "core/image_io.h"
#include "export/lightmap_encoding.h"
#include "metrics/metrics.h"
#include "support/paths.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

using namespace vl;

TEST_CASE("RGBM keeps every value from the range down to range / 255 within 0.4%", "[export]") {
    // The largest channel is stored as c / (a · range) with a rounded up to 1/255 steps, so
    // it lands in (254/255, 1] where it holds a value above range / 255: its 8 bits err at most
    // half a step of 1/254 of the value (0.2%); the other channels of a grey texel likewise.
    Image linear(256, 1, 3);
    for (int x = 0; x < 256; ++x) {
        const float v = 6.0f * std::pow(255.0f, -float(x) / 255.0f);  // 6 down to 6 / 255
        linear.setRgb(x, 0, vec3(v));
    }
    const RgbmImage encoded = encodeRgbm(linear);
    CHECK(encoded.range == 8.0f);  // the power of two above 6
    const Image decoded = decodeRgbm(encoded);
    for (int x = 0; x < 256; ++x) {
        INFO("value " << linear.at(x, 0) << " decodes to " << decoded.at(x, 0));
        CHECK(decoded.at(x, 0, 0) == Approx(linear.at(x, 0, 0)).epsilon(0.004));
    }
}

TEST_CASE("RGBM stores black, negative and non-finite texels as black, and a dim map in range 1", "[export]") {
    Image linear(4, 1, 3);
    linear.setRgb(0, 0, vec3(0.0f));
    linear.setRgb(1, 0, vec3(-1.0f, 0.2f, -0.5f));
    linear.setRgb(2, 0, vec3(std::numeric_limits<float>::quiet_NaN(), 0.1f, std::numeric_limits<float>::infinity()));
    linear.setRgb(3, 0, vec3(0.25f, 0.5f, 0.125f));
    const RgbmImage encoded = encodeRgbm(linear);
    CHECK(encoded.range == 1.0f);
    const Image decoded = decodeRgbm(encoded);
    CHECK(decoded.rgb(0, 0) == vec3(0.0f));
    CHECK(decoded.at(1, 0, 0) == 0.0f);
    CHECK(decoded.at(1, 0, 1) == Approx(0.2f).epsilon(0.004));
    CHECK(decoded.at(2, 0, 0) == 0.0f);
    CHECK(decoded.at(2, 0, 2) == 0.0f);
    for (int c = 0; c < 3; ++c) CHECK(decoded.at(3, 0, c) == Approx(linear.at(3, 0, c)).epsilon(0.01));
}

TEST_CASE("The Cornell boxes' lightmaps come back from an RGBM PNG within 1% relative RMSE", "[export]") {
    // Issue 14's bound, over the covered texels of Cycles' own lightmaps of both boxes (the
    // bake's lightmaps are held to it where the bake writes scene.glb: tests/bake).
    VL_SKIP_WITHOUT_SHARED();
    for (const std::string box : {"quad", "point"}) {
        const std::string dir = test::sharedDir() + "/reference/cycles/cornell_" + box;
        const Image lightmap = readImage(dir + "_lightmap_4096spp.exr");
        const Image mask = readImage(dir + "_lightmap_mask.exr");
        const RgbmImage encoded = encodeRgbm(lightmap);
        const std::string png = test::tempDir("rgbm") + "/" + box + ".png";
        {
            const std::vector<uint8_t> bytes = rgbmPng(encoded);
            std::FILE* file = std::fopen(png.c_str(), "wb");
            REQUIRE(file);
            REQUIRE(std::fwrite(bytes.data(), 1, bytes.size(), file) == bytes.size());
            std::fclose(file);
        }
        const RgbmImage read = readRgbmPng(png, encoded.range);
        CHECK(read.rgba == encoded.rgba);  // the PNG keeps the bytes: no alpha association
        Image rgb(lightmap.width, lightmap.height, 3);
        for (int y = 0; y < rgb.height; ++y)
            for (int x = 0; x < rgb.width; ++x) rgb.setRgb(x, y, lightmap.rgb(x, y));
        MetricOptions options;
        options.mask = &mask;
        const double error = relativeRmse(decodeRgbm(read), rgb, options);
        INFO(box << ": range " << encoded.range << ", relative RMSE " << error);
        CHECK(error < 0.01);
    }
}
