// The rays a gather point sends (its fan) and what each reads where it hits a surface: the
// level-0 voxel texels that show the hit surface's side facing back at the ray. Written once
// for the gathers by rays on the host (ray_gather.cpp, through a flat table of the voxels'
// coverage) and for a receiver sample no gather point applies to (shade_element.h, through
// the level's index grid, on the host or a GPU).
#pragma once

#include "cone/radiance_mips.h"
#include "core/hostdev.h"
#include "core/math.h"
#include "core/sampling.h"

#include <cstdint>

namespace vl {

// A fan's frame about its unit normal: `tangent` (unit, ⊥ normal) turned by `turn` of a full
// turn, and the bitangent that completes it.
struct FanFrame {
    vec3 normal, tangent, bitangent;
};

VL_HOSTDEV inline FanFrame fanFrame(const vec3& normal, const vec3& tangent, float turn) {
    const float angle = 2.0f * kPi * turn;
    const vec3 across = glm::cross(normal, tangent);
    FanFrame frame;
    frame.normal = normal;
    frame.tangent = std::cos(angle) * tangent + std::sin(angle) * across;
    frame.bitangent = glm::cross(normal, frame.tangent);
    return frame;
}

// Ray (i, j) of an n × n fan about +Z: one per stratum of the square, whose cosine-distributed
// directions (sampleCosineHemisphere) the ray stands for with weight π/n², pointing at their
// mean elevation and mean azimuth (over kFanStratumSamples² points of the stratum). Why not
// the stratum's middle: the outer ring of strata spans 59–90° from the normal at n = 14, and
// its middle maps to 68°, its mean elevation is 69°, so the fan read the grazing directions,
// where a room's corners are dark, at steeper ones and over-counted the brighter light there
// (docs/decisions.md, "Where walls fall in the gather cells"). A constant radiance still
// gathers exactly π·L: every ray keeps its weight.
constexpr int kFanStratumSamples = 4;
VL_HOSTDEV inline vec3 fanDirection(int i, int j, int n) {
    float elevation = 0.0f;
    vec2 azimuth(0.0f);
    for (int a = 0; a < kFanStratumSamples; ++a)
        for (int b = 0; b < kFanStratumSamples; ++b) {
            const vec2 d = sampleConcentricDisk(vec2((float(i) + (float(a) + 0.5f) / kFanStratumSamples) / float(n),
                                                     (float(j) + (float(b) + 0.5f) / kFanStratumSamples) / float(n)));
            const float r = glm::min(1.0f, glm::length(d));
            elevation += glm::asin(r);
            if (r > 0.0f) azimuth += d / r;
        }
    // The stratum around the disk's centre (n odd) has no mean azimuth: its samples' cancel to
    // rounding, and its ray is the normal.
    const float length = glm::length(azimuth);
    if (!(length > 0.5f)) return vec3(0.0f, 0.0f, 1.0f);
    elevation /= float(kFanStratumSamples * kFanStratumSamples);
    return vec3(azimuth / length * glm::sin(elevation), glm::cos(elevation));
}

// Ray (i, j) of an n × n fan about +Z at the point `jitter` ∈ [0, 1)² of its stratum, mapped to
// the cosine-weighted hemisphere: with one jitter per fan, uniform over the fans, each ray is
// uniform in its stratum, so the fan's estimate is unbiased. The fixed rays above are a
// quadrature: a small bright source (a sun in a sky image) falls in or between the same rings
// of elevation at every point of a floor and biases its mean (docs/accuracy.md).
VL_HOSTDEV inline vec3 fanDirectionJittered(int i, int j, int n, const vec2& jitter) {
    const vec2 d = sampleConcentricDisk(vec2((float(i) + jitter.x) / float(n), (float(j) + jitter.y) / float(n)));
    return vec3(d, glm::sqrt(glm::max(0.0f, 1.0f - glm::dot(d, d))));
}

// A fan direction about +Z laid out in `frame`.
VL_HOSTDEV inline vec3 inFrame(const FanFrame& frame, const vec3& d) {
    return glm::normalize(d.x * frame.tangent + d.y * frame.bitangent + d.z * frame.normal);
}

// Along each axis a (weight n_a², normalised over the axes read), the level-0 texel that shows
// the face of the hit surface's side that looks back at the ray (radiance_mips.h: the texel of
// travel −s shows face s), in the voxel holding the hit or its neighbour along a, whichever
// shows more surface; its colour is radiance / coverage. Calls read(voxel, travel, weight) per
// texel read; n (the hit surface's geometric normal) need not be unit. The face follows the
// surface's side, not the ray's sign along each axis: a ray glancing down onto a tilted
// double-sided floor travels +X where the floor's lit side faces +X, and the texel of its
// travel would show the floor's unlit underside, and a turned double-sided box lost much of
// its bounce series that way (docs/decisions.md, "Rotations by rays"). Only the voxels the
// surface itself passes through are read, so nothing behind the surface (a thin wall's other
// room) is.
//
// Lookup gives voxelAt(leaves, voxel) (its index, −1 where none), coverage(index, travel) (of
// type Lookup::Coverage, kWhole where the texel shows its face whole) and inverseVoxelSize.
template <typename Lookup, typename Read>
VL_HOSTDEV inline void readHitTexels(const Lookup& level0, IndexLeafCache& leaves, const vec3& hitPoint,
                                     const vec3& direction, const vec3& n, Read&& read) {
    using Coverage = typename Lookup::Coverage;
    const ivec3 centre(glm::floor(hitPoint * level0.inverseVoxelSize + vec3(0.5f)));
    const float length2 = glm::dot(n, n);
    const vec3 seen = glm::dot(n, direction) < 0.0f ? n : -n;  // the side facing the ray
    int32_t voxel[3];
    float weight[3];
    int travel[3];
    float weights = 0.0f;
    for (int a = 0; a < 3; ++a) {
        voxel[a] = -1;
        const float w = n[a] * n[a];
        if (!(w > 0.01f * length2)) continue;
        travel[a] = 2 * a + (seen[a] > 0.0f ? 1 : 0);
        Coverage best = Coverage(0);
        // The hit's own voxel first: where it shows the face whole (no voxel shows more) its
        // neighbours are not looked up, which most hits on a wall are spared; the lookups were
        // much of the trace's time (docs/speed.md, "The ray gather's memory reads").
        for (int k : {0, -1, 1}) {
            ivec3 c = centre;
            c[a] += k;
            const int32_t index = level0.voxelAt(leaves, c);
            if (index < 0) continue;
            const Coverage coverage = level0.coverage(index, travel[a]);
            if (coverage > best) {
                best = coverage;
                voxel[a] = index;
                if (coverage >= Lookup::kWhole) break;
            }
        }
        if (voxel[a] >= 0) {
            weight[a] = w;
            weights += w;
        }
    }
    for (int a = 0; a < 3; ++a)
        if (voxel[a] >= 0) read(voxel[a], travel[a], weight[a] / weights);
}

// A mip level 0 read through its own index grid and texels (host or device memory).
struct Level0Texels {
    using Coverage = float;
    static constexpr float kWhole = 1.0f;
    MipLevelView level;
    float inverseVoxelSize = 0.0f;

    VL_HOSTDEV explicit Level0Texels(const MipLevelView& view) : level(view), inverseVoxelSize(view.inverseVoxelSize) {}
    VL_HOSTDEV int32_t voxelAt(IndexLeafCache& leaves, const ivec3& c) const {
        return leaves.value(*level.index, nanovdb::Coord(c.x, c.y, c.z));
    }
    VL_HOSTDEV float coverage(int32_t voxel, int travel) const {
        return glm::clamp(level.texels[size_t(voxel) * size_t(level.facesPerVoxel) + size_t(travel)].coverage, 0.0f, 1.0f);
    }
    // The face's radiance: the texel's, over its coverage.
    VL_HOSTDEV vec3 colour(int32_t voxel, int travel) const {
        const MipTexel& t = level.texels[size_t(voxel) * size_t(level.facesPerVoxel) + size_t(travel)];
        return t.coverage > 0.0f ? t.radiance / t.coverage : vec3(0.0f);
    }
};

}  // namespace vl
