// Lightmaps for glTF out: takes a linear float lightmap (the bake's EXR), gives RGBM in 8-bit
// RGBA, the encoding a glTF's PNG can carry with the lightmap's dynamic range.
//
// RGBM (three.js RGBMToLinear, maxRange = range): linear = rgb · a · range, rgb and a in
// [0, 1], stored linear (no sRGB curve). range is the smallest power of two at or above the
// lightmap's brightest value (at least 1), so a texel's largest channel is stored at 8 bits
// of its own brightness (rgb's largest channel ≥ 254/255 after rounding a up), and a texel
// as dim as range / 255² still keeps a few percent. Why not sRGB LDR scaled by the maximum:
// a hot spot 20 times the mean (a light on a ceiling) leaves the rest of the map a few
// levels. Why not RGBE: its shared exponent needs the same custom decode as RGBM and a
// browser's 8-bit alpha handles neither better; RGBM is what three.js decodes already.
#pragma once

#include "core/image.h"

#include <cstdint>
#include <string>
#include <vector>

namespace vl {

struct RgbmImage {
    int width = 0;
    int height = 0;
    float range = 1.0f;          // linear = rgb · a · range
    std::vector<uint8_t> rgba;   // 4 per texel, rows from the top
};

// Of an image's first three channels (1 or 2 channels: grey). Non-finite and negative
// values are taken as 0.
RgbmImage encodeRgbm(const Image& linear);
// Back to linear RGB (3 channels).
Image decodeRgbm(const RgbmImage& encoded);

// An 8-bit RGBA PNG of the encoded texels, in memory, as stored (no alpha association, no
// sRGB curve): what a .glb embeds.
std::vector<uint8_t> rgbmPng(const RgbmImage& encoded);
// A shadowmask (gather/shadowmask.h: RGBA visibility 0..1) as 8-bit linear RGBA, each channel
// rounded to the nearest 1/255: what scene.glb and <atlas>_shadowmask.png carry.
std::vector<uint8_t> shadowmaskBytes(const Image& mask);
// Those bytes back to 0..1 (4 channels).
Image decodeShadowmask(int width, int height, const std::vector<uint8_t>& bytes);

// Reads such a PNG back (the range is not in the file: the glTF carries it). InputError
// naming the path for a file that is not 8-bit RGBA.
RgbmImage readRgbmPng(const std::string& path, float range);

}  // namespace vl
