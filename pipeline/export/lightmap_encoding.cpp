#include "export/lightmap_encoding.h"

#include "core/error.h"
#include "core/image_io.h"

#include <algorithm>
#include <cmath>

namespace vl {

namespace {

vec3 texelRgb(const Image& image, int x, int y) {
    vec3 c;
    for (int k = 0; k < 3; ++k) {
        const float v = image.at(x, y, std::min(k, image.channels - 1));
        c[k] = std::isfinite(v) && v > 0.0f ? v : 0.0f;
    }
    return c;
}

}  // namespace

RgbmImage encodeRgbm(const Image& linear) {
    RgbmImage out;
    out.width = linear.width;
    out.height = linear.height;
    if (linear.channels < 1) throw Error("encodeRgbm: an image without channels");
    float brightest = 0.0f;
    for (int y = 0; y < linear.height; ++y)
        for (int x = 0; x < linear.width; ++x) brightest = std::max(brightest, maxComponent(texelRgb(linear, x, y)));
    out.range = 1.0f;
    while (out.range < brightest && out.range < 65536.0f) out.range *= 2.0f;
    out.rgba.assign(static_cast<size_t>(out.width) * static_cast<size_t>(out.height) * 4, 0);
    for (int y = 0; y < linear.height; ++y)
        for (int x = 0; x < linear.width; ++x) {
            const vec3 c = glm::min(texelRgb(linear, x, y), vec3(out.range));
            const float m = maxComponent(c) / out.range;
            uint8_t* texel = &out.rgba[(static_cast<size_t>(y) * static_cast<size_t>(out.width) + static_cast<size_t>(x)) * 4];
            if (!(m > 0.0f)) continue;  // black: rgb 0, a 0
            // a rounded up, so rgb = c / (a · range) stays within 1 and its largest channel
            // keeps 8 bits of the texel's own brightness.
            const int a = std::clamp(static_cast<int>(std::ceil(m * 255.0f)), 1, 255);
            const float scale = 255.0f / (float(a) / 255.0f * out.range);
            for (int k = 0; k < 3; ++k)
                texel[k] = static_cast<uint8_t>(std::clamp(std::lround(c[k] * scale), 0L, 255L));
            texel[3] = static_cast<uint8_t>(a);
        }
    return out;
}

Image decodeRgbm(const RgbmImage& encoded) {
    Image out(encoded.width, encoded.height, 3);
    const float unit = encoded.range / (255.0f * 255.0f);
    for (int y = 0; y < encoded.height; ++y)
        for (int x = 0; x < encoded.width; ++x) {
            const uint8_t* texel =
                &encoded.rgba[(static_cast<size_t>(y) * static_cast<size_t>(encoded.width) + static_cast<size_t>(x)) * 4];
            for (int k = 0; k < 3; ++k) out.at(x, y, k) = float(texel[k]) * float(texel[3]) * unit;
        }
    return out;
}

std::vector<uint8_t> shadowmaskBytes(const Image& mask) {
    if (mask.channels != 4) throw Error("shadowmaskBytes: a shadowmask has 4 channels, this one " + std::to_string(mask.channels));
    std::vector<uint8_t> bytes(mask.pixels.size());
    for (size_t k = 0; k < bytes.size(); ++k) {
        const float v = mask.pixels[k];
        bytes[k] = static_cast<uint8_t>(std::clamp(std::lround((v > 0.0f ? std::min(v, 1.0f) : 0.0f) * 255.0f), 0L, 255L));
    }
    return bytes;
}

Image decodeShadowmask(int width, int height, const std::vector<uint8_t>& bytes) {
    Image out(width, height, 4);
    if (bytes.size() != out.pixels.size()) throw Error("decodeShadowmask: the bytes are not the image's size");
    for (size_t k = 0; k < bytes.size(); ++k) out.pixels[k] = float(bytes[k]) / 255.0f;
    return out;
}

std::vector<uint8_t> rgbmPng(const RgbmImage& encoded) {
    return encodePng8(encoded.width, encoded.height, 4, encoded.rgba);
}

RgbmImage readRgbmPng(const std::string& path, float range) {
    RgbmImage image;
    int channels = 0;
    image.rgba = readImage8(path, image.width, image.height, channels);
    if (channels != 4) throw InputError(path + ": an RGBM lightmap has 4 channels, this one " + std::to_string(channels));
    image.range = range;
    return image;
}

}  // namespace vl
