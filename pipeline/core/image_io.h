// Image files through OpenImageIO. Writers go through a temporary name and rename, so a
// failed or interrupted job never leaves a half-written file that looks finished.
#pragma once

#include "core/image.h"

#include <cstdint>
#include <string>
#include <vector>

namespace vl {

// Linear float EXR; channel names default to R, G, B, A by channel count.
void writeExr(const Image& image, const std::string& path, const std::vector<std::string>& channelNames = {});
// 8-bit sRGB-encoded PNG preview of linear values (clamped to [0, 1] after encoding).
void writePngSrgb(const Image& image, const std::string& path);
// Any format OpenImageIO reads, as float. 8-bit files are returned as stored (no decoding).
Image readImage(const std::string& path);
// The same, as linear light: float files (EXR, HDR) as stored, integer ones (PNG, JPEG, 8- or
// 16-bit TIFF) decoded from sRGB as Blender reads them; alpha as stored.
Image readLinearImage(const std::string& path);
// An 8-bit PNG, in memory, of `texels` (`channels` per pixel, rows from the top) exactly as
// given: no sRGB curve, alpha not associated (an encoding that keeps colour under a small
// alpha, RGBM, needs both). Error when it cannot be encoded.
std::vector<uint8_t> encodePng8(int width, int height, int channels, const std::vector<uint8_t>& texels);
// The 8-bit texels of an encoded image in memory (PNG, JPEG) as stored; InputError naming
// `what` when it does not decode.
std::vector<uint8_t> decodeImage8(const std::vector<uint8_t>& bytes, const std::string& what, int& width, int& height,
                                  int& channels);
// The 8-bit texels of an image file as stored (alpha not associated, no curve applied);
// InputError naming the path.
std::vector<uint8_t> readImage8(const std::string& path, int& width, int& height, int& channels);

}  // namespace vl
