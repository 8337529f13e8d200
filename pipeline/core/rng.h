// PCG32 (O'Neill 2014). Every pixel, texel and voxel seeds its own generator from its
// index and sample number, so results never depend on thread count or work split.
#pragma once

#include "core/hostdev.h"

#include <cstdint>

namespace vl {

VL_HOSTDEV inline uint64_t splitMix64(uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

class Pcg32 {
public:
    VL_HOSTDEV Pcg32(uint64_t seed, uint64_t stream) {
        state_ = 0u;
        inc_ = (stream << 1u) | 1u;
        nextU32();
        state_ += seed;
        nextU32();
    }

    // Generator for item `index` (pixel, texel, voxel) at sample `sample` of a pass `salt`.
    VL_HOSTDEV static Pcg32 forItem(uint64_t index, uint64_t sample, uint64_t salt = 0) {
        return Pcg32(splitMix64(index ^ splitMix64(salt)), splitMix64(sample + 0x5851F42D4C957F2Dull * salt));
    }

    VL_HOSTDEV uint32_t nextU32() {
        const uint64_t old = state_;
        state_ = old * 6364136223846793005ull + inc_;
        const uint32_t xorShifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
        const uint32_t rot = static_cast<uint32_t>(old >> 59u);
        return (xorShifted >> rot) | (xorShifted << ((~rot + 1u) & 31u));
    }

    // Uniform in [0, 1): 24 random bits, so the result is never rounded up to 1.
    VL_HOSTDEV float next1D() { return static_cast<float>(nextU32() >> 8) * 0x1p-24f; }

    // Two draws, x first. Why not vec2(next1D(), next1D()): the order in which a call's
    // arguments are evaluated is unspecified, and g++ (host) and nvcc (device) chose
    // differently, so the same seed gave the CPU and the GPU different points.
    VL_HOSTDEV void next2D(float& x, float& y) {
        x = next1D();
        y = next1D();
    }

private:
    uint64_t state_;
    uint64_t inc_;
};

}  // namespace vl
