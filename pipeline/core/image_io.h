// Image files through OpenImageIO. Writers go through a temporary name and rename, so a
// failed or interrupted job never leaves a half-written file that looks finished.
#pragma once

#include "core/image.h"

#include <string>
#include <vector>

namespace vl {

// Linear float EXR; channel names default to R, G, B, A by channel count.
void writeExr(const Image& image, const std::string& path, const std::vector<std::string>& channelNames = {});
// 8-bit sRGB-encoded PNG preview of linear values (clamped to [0, 1] after encoding).
void writePngSrgb(const Image& image, const std::string& path);
// Any format OpenImageIO reads, as float. 8-bit files are returned as stored (no decoding).
Image readImage(const std::string& path);

}  // namespace vl
