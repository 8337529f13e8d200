// A linear float image, row-major from the top row, channels interleaved.
#pragma once

#include "core/math.h"

#include <string>
#include <vector>

namespace vl {

struct Image {
    int width = 0;
    int height = 0;
    int channels = 0;
    std::vector<float> pixels;

    Image() = default;
    Image(int w, int h, int c, float fill = 0.0f)
        : width(w), height(h), channels(c), pixels(static_cast<size_t>(w) * h * c, fill) {}

    size_t index(int x, int y, int c = 0) const { return (static_cast<size_t>(y) * width + x) * channels + c; }
    float& at(int x, int y, int c = 0) { return pixels[index(x, y, c)]; }
    float at(int x, int y, int c = 0) const { return pixels[index(x, y, c)]; }
    vec3 rgb(int x, int y) const { return vec3(at(x, y, 0), at(x, y, 1), at(x, y, 2)); }
    void setRgb(int x, int y, const vec3& v) { at(x, y, 0) = v.x; at(x, y, 1) = v.y; at(x, y, 2) = v.z; }
    bool empty() const { return pixels.empty(); }
};

float srgbToLinear(float c);
float linearToSrgb(float c);

}  // namespace vl
