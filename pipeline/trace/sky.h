// What a ray that leaves the scene sees: a uniform radiance plus, optionally, an
// equirectangular image turned about +Y and scaled (scene.h Sky). The kernels' side: look up,
// importance-sample and give the pdf of a direction (VL_HOSTDEV, no allocation).
//
// The image's mapping is Blender's (Cycles' environment texture, equirectangular, as the
// glTF importer places the scene: glTF (x, y, z) is Blender (x, −z, y)), so an HDR looks the
// same in voxlight as in Blender. For a unit direction e in the image's frame:
//   column = W·(½ + atan2(e.z, e.x)/2π)   (0 at the image's left edge)
//   row    = H·acos(e.y)/π                 (0 at the top edge: straight up)
// The image's centre looks along +X, its left quarter along −Z. A rotation of θ turns the sky
// counterclockwise seen from above: L(d) = intensity·image(R_y(−θ)·d) + uniform. Lookups are
// bilinear between pixel centres, wrapping around in azimuth (Cycles' Linear interpolation).
//
// Sampling draws a pixel in proportion to its luminance × sin θ (its solid angle), then a
// uniform point of it in (column, row): pdf(d) = p(pixel)·W·H / (2π²·sin θ) in solid angle.
#pragma once

#include "core/math.h"

namespace vl {

struct SkyView {
    vec3 uniform{0.0f};           // W/(m²·sr) in every direction
    const vec3* texels = nullptr;  // width × height, rows from the top; null: no image
    int width = 0, height = 0;
    float intensity = 1.0f;
    // The rows of the rotation from the scene's local frame to the image's: the frame to the
    // world (Scene::frame), then R_y(−θ) for the image's rotation θ.
    vec3 toImageRows[3] = {vec3(1.0f, 0.0f, 0.0f), vec3(0.0f, 1.0f, 0.0f), vec3(0.0f, 0.0f, 1.0f)};
    // Sampling tables (null when the image is black): per row the inclusive marginal CDF
    // (rowCdf[height - 1] = 1), per row and column the inclusive conditional CDF.
    const float* rowCdf = nullptr;
    const float* columnCdf = nullptr;

    VL_HOSTDEV bool hasImage() const { return texels != nullptr && width > 0 && height > 0; }
    VL_HOSTDEV bool samplable() const { return hasImage() && rowCdf != nullptr && columnCdf != nullptr; }
    VL_HOSTDEV bool present() const { return maxComponent(uniform) > 0.0f || (hasImage() && intensity > 0.0f); }

    // A local direction to the image's frame and back.
    VL_HOSTDEV vec3 toImage(const vec3& d) const {
        return vec3(glm::dot(toImageRows[0], d), glm::dot(toImageRows[1], d), glm::dot(toImageRows[2], d));
    }
    VL_HOSTDEV vec3 fromImage(const vec3& e) const {
        return e.x * toImageRows[0] + e.y * toImageRows[1] + e.z * toImageRows[2];
    }
    // Continuous (column, row) of an image-frame unit direction.
    VL_HOSTDEV vec2 imageCoordinates(const vec3& e) const {
        const float u = 0.5f + glm::atan(e.z, e.x) * (0.5f * kInvPi);
        const float v = glm::acos(glm::clamp(e.y, -1.0f, 1.0f)) * kInvPi;
        return vec2(u * float(width), v * float(height));
    }
    VL_HOSTDEV vec3 texel(int column, int row) const {
        column %= width;
        if (column < 0) column += width;
        row = glm::clamp(row, 0, height - 1);
        return texels[size_t(row) * size_t(width) + size_t(column)];
    }
};

// Radiance at continuous image coordinates (column, row), the uniform part included.
VL_HOSTDEV inline vec3 skyRadianceAt(const SkyView& sky, vec2 coordinates) {
    const vec2 p = coordinates - vec2(0.5f);
    const float fx = glm::floor(p.x), fy = glm::floor(p.y);
    const int x = int(fx), y = int(fy);
    const float tx = p.x - fx, ty = p.y - fy;
    const vec3 top = (1.0f - tx) * sky.texel(x, y) + tx * sky.texel(x + 1, y);
    const vec3 bottom = (1.0f - tx) * sky.texel(x, y + 1) + tx * sky.texel(x + 1, y + 1);
    return sky.uniform + sky.intensity * ((1.0f - ty) * top + ty * bottom);
}

// Radiance seen along unit direction d.
VL_HOSTDEV inline vec3 skyRadianceAlong(const SkyView& sky, const vec3& d) {
    if (!sky.hasImage()) return sky.uniform;
    return skyRadianceAt(sky, sky.imageCoordinates(sky.toImage(d)));
}

// First index whose inclusive CDF value exceeds u (the last where rounding leaves none).
// Branch-free halving (a conditional move per step): a branchy search's mispredictions cost
// the receivers much of their time under an image sky (docs/decisions.md, "Sky sampling").
VL_HOSTDEV inline int searchCdf(const float* cdf, int n, float u) {
    int base = 0;
    for (int length = n; length > 1;) {
        const int half = length / 2;
        base = cdf[base + half - 1] <= u ? base + half : base;
        length -= half;
    }
    return base;
}

VL_HOSTDEV inline float cdfStep(const float* cdf, int i) { return cdf[i] - (i > 0 ? cdf[i - 1] : 0.0f); }

// Solid-angle pdf of a uniform point of a pixel drawn with probability `pixel`, at polar sine
// sin θ: the pixel spans 2π/W × π/H in (φ, θ), dω = sin θ dθ dφ.
VL_HOSTDEV inline float skyPixelPdf(const SkyView& sky, float pixel, float sinTheta) {
    return pixel * float(sky.width) * float(sky.height) / (2.0f * kPi * kPi * sinTheta);
}

// The solid-angle pdf of drawing the image-frame direction at `coordinates`, sin θ its
// polar sine (0 without tables).
VL_HOSTDEV inline float skyImagePdfAt(const SkyView& sky, vec2 coordinates, float sinTheta) {
    if (!sky.samplable() || !(sinTheta > 0.0f)) return 0.0f;
    const int row = glm::clamp(int(coordinates.y), 0, sky.height - 1);
    const int column = glm::clamp(int(coordinates.x), 0, sky.width - 1);
    return skyPixelPdf(sky, cdfStep(sky.rowCdf, row) * cdfStep(sky.columnCdf + size_t(row) * size_t(sky.width), column),
                       sinTheta);
}

// What the sky shows along unit direction d and the pdf of the image's draws there, from one
// mapping of d (the receivers' cosine directions need both).
struct SkySeen {
    vec3 radiance;
    float imagePdf;
};
VL_HOSTDEV inline SkySeen skySeenAlong(const SkyView& sky, const vec3& d) {
    if (!sky.hasImage()) return {sky.uniform, 0.0f};
    const vec3 e = sky.toImage(d);
    const vec2 c = sky.imageCoordinates(e);
    return {skyRadianceAt(sky, c), skyImagePdfAt(sky, c, glm::sqrt(glm::max(0.0f, 1.0f - e.y * e.y)))};
}

// The solid-angle pdf with which sampleSkyImage draws unit direction d (0 without tables).
VL_HOSTDEV inline float skyImagePdf(const SkyView& sky, const vec3& d) { return skySeenAlong(sky, d).imagePdf; }

// A direction drawn from the image's distribution at u ∈ [0, 1)²; pdf its solid-angle pdf
// (0: nothing drawn); `coordinates`, when given, its image coordinates (for skyRadianceAt).
VL_HOSTDEV inline vec3 sampleSkyImage(const SkyView& sky, vec2 u, float& pdf, vec2* coordinates = nullptr) {
    pdf = 0.0f;
    if (!sky.samplable()) return vec3(0.0f, 1.0f, 0.0f);
    const int row = searchCdf(sky.rowCdf, sky.height, u.x);
    const float rowP = cdfStep(sky.rowCdf, row), rowLow = sky.rowCdf[row] - rowP;
    const float* columns = sky.columnCdf + size_t(row) * size_t(sky.width);
    const int column = searchCdf(columns, sky.width, u.y);
    const float columnP = cdfStep(columns, column), columnLow = columns[column] - columnP;
    if (!(rowP > 0.0f) || !(columnP > 0.0f)) return vec3(0.0f, 1.0f, 0.0f);
    // The same uniforms, rescaled within the chosen row and column, place the point inside it.
    const float fy = glm::clamp((u.x - rowLow) / rowP, 0.0f, 1.0f);
    const float fx = glm::clamp((u.y - columnLow) / columnP, 0.0f, 1.0f);
    const float theta = (float(row) + fy) / float(sky.height) * kPi;
    const float phi = ((float(column) + fx) / float(sky.width) - 0.5f) * 2.0f * kPi;
    const float sinTheta = glm::sin(theta);
    if (!(sinTheta > 0.0f)) return vec3(0.0f, 1.0f, 0.0f);
    const vec3 e(sinTheta * glm::cos(phi), glm::cos(theta), sinTheta * glm::sin(phi));
    pdf = skyPixelPdf(sky, rowP * columnP, sinTheta);
    if (coordinates) *coordinates = vec2(float(column) + fx, float(row) + fy);
    return sky.fromImage(e);
}

}  // namespace vl
