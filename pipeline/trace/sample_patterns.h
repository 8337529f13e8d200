// Stratified sample patterns for the dimensions where stratification pays most: the pixel
// position (an edge or a small emitter crossing a pixel converges at ~N^-3/4 instead of
// N^-1/2) and the lens. Sample j of n takes point j of a low-discrepancy set (Hammersley
// for the pixel, Halton bases 3 and 5 for the lens), shifted by a per-pixel uniform offset
// modulo 1 (Cranley–Patterson rotation): every sample is still uniform, so the estimator
// stays unbiased, and the pattern depends only on (pixel, j, n), never on threads.
#pragma once

#include "core/math.h"

#include <cstdint>

namespace vl {

VL_HOSTDEV inline float radicalInverseBase2(uint32_t i) {
    i = (i << 16u) | (i >> 16u);
    i = ((i & 0x00ff00ffu) << 8u) | ((i & 0xff00ff00u) >> 8u);
    i = ((i & 0x0f0f0f0fu) << 4u) | ((i & 0xf0f0f0f0u) >> 4u);
    i = ((i & 0x33333333u) << 2u) | ((i & 0xccccccccu) >> 2u);
    i = ((i & 0x55555555u) << 1u) | ((i & 0xaaaaaaaau) >> 1u);
    return static_cast<float>(i >> 8) * 0x1p-24f;
}

VL_HOSTDEV inline float radicalInverse(uint32_t base, uint32_t i) {
    const float inverseBase = 1.0f / static_cast<float>(base);
    float factor = inverseBase;
    float result = 0.0f;
    while (i > 0) {
        result += static_cast<float>(i % base) * factor;
        i /= base;
        factor *= inverseBase;
    }
    return glm::min(result, 0x1.fffffep-1f);
}

// (a + b) mod 1 for a, b in [0, 1), kept below 1 in float.
VL_HOSTDEV inline float addModOne(float a, float b) {
    const float s = a + b;
    return glm::min(s >= 1.0f ? s - 1.0f : s, 0x1.fffffep-1f);
}

// Point j of the n-point Hammersley set, rotated by `shift`.
VL_HOSTDEV inline vec2 rotatedHammersley(uint32_t j, uint32_t n, vec2 shift) {
    const float x = static_cast<float>(j) / static_cast<float>(n);
    return vec2(addModOne(x, shift.x), addModOne(radicalInverseBase2(j), shift.y));
}

// Point j of the Halton sequence in bases 3 and 5, rotated by `shift`.
VL_HOSTDEV inline vec2 rotatedHalton35(uint32_t j, vec2 shift) {
    return vec2(addModOne(radicalInverse(3, j), shift.x), addModOne(radicalInverse(5, j), shift.y));
}

}  // namespace vl
