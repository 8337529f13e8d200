// Cone marching through the radiance mips (DESIGN.md "Cone tracing"), written once for the
// TBB pass and the CUDA launchers: takes a MipView (radiance_mips.h), a ConeSet
// (cone_set.h) and ConeSettings; gives the radiance a cone gathers and the irradiance at a
// receiver (p, n). traceCone says how one cone marches: it samples one level finer than its
// width, one level rather than a blend of two, and corrects each sample's opacity for its
// step, so a uniform medium is Beer–Lambert at every level.
#pragma once

#include "cone/cone_set.h"
#include "cone/cone_settings.h"
#include "cone/radiance_mips.h"
#include "core/rng.h"

namespace vl {

// Cones sample one level finer than their diameter (traceCone says why).
constexpr float kConeLevelOffset = 1.0f;
constexpr float kConeLevelScale = 0.5f;  // 2^−kConeLevelOffset: level = log2(D·scale / h)

struct ConeResult {
    vec3 radiance = vec3(0.0f);  // Σ (1 − A)·c': what the cone sees, α-composited
    float occlusion = 0.0f;      // A in [0, 1]
};

// Trilinear sample of one level at index-space position x (voxel centres at integers).
// Each voxel read shows the texels of the faces that look back at the viewer, blended by the
// squared components of the direction u from the viewer to that voxel (the three faces u
// points along; radiance_mips.h stores the texel seen travelling along +X, −X, … ). The
// viewer is `viewpoint` (index space at this level; the cone's apex) when given, else far
// away against `dir` (u = dir for every voxel). Why the apex and not the travel direction:
// the trilinear footprint reaches voxels beside and behind the sample point, and a wall the
// cone runs along or away from is seen from the apex's side of it, never from the far side
// (by travel direction, a cone leaving the dark side of a wall lit on its other side read
// the lit face of the wall behind it). Absent voxels are zero. The sample's colour is
// radiance / coverage: the surfaces it shows, weighted by how much of each texel is surface;
// a sample showing only faces without surface is dark (the back of a one-sided surface).
// `density` is the trilinear optical depth σ, not σ of the trilinear α: σ is what adds up
// along a ray, and interpolating α instead turns a solid wall one voxel thick into a tent
// whose transmittance is e^−2 ≈ 14 % at every level (light leaks through every thin wall).
struct MipSample {
    vec3 radiance = vec3(0.0f);  // coverage-premultiplied
    float alpha = 0.0f;
    float density = 0.0f;
    float coverage = 0.0f;

    VL_HOSTDEV vec3 colour() const { return coverage > 0.0f ? radiance / coverage : vec3(0.0f); }
};

// The three travel texels a viewer looking along u sees and their weights (Σ = 1; an axis u
// has no part along gets weight 0).
VL_HOSTDEV inline void viewFaces(const vec3& u, int (&faces)[3], float (&weights)[3]) {
    float sum = 0.0f;
    for (int a = 0; a < 3; ++a) {
        faces[a] = 2 * a + (u[a] < 0.0f ? 1 : 0);
        weights[a] = u[a] * u[a];
        sum += weights[a];
    }
    for (int a = 0; a < 3; ++a) weights[a] = sum > 0.0f ? weights[a] / sum : 1.0f / 3.0f;
}

VL_HOSTDEV inline MipSample sampleMipLevel(const MipLevelView& level, IndexLeafCache& leaves, const vec3& x,
                                           const vec3& dir, const vec3* viewpoint = nullptr) {
    constexpr float kIndexLimit = 1.0e9f;  // keeps the int conversion defined far outside
    MipSample sum;
    if (!(glm::abs(x.x) < kIndexLimit && glm::abs(x.y) < kIndexLimit && glm::abs(x.z) < kIndexLimit)) return sum;

    const vec3 base = glm::floor(x);
    const vec3 f = x - base;
    const ivec3 i0(base);
    // The eight corners' texel indices; where they share a leaf (7 samples in 8 with
    // 8³ leaves), one leaf lookup serves all of them.
    using Leaf = IndexLeafCache::Leaf;
    int32_t indices[8];
    constexpr int kLast = int(Leaf::MASK);
    if ((i0.x & kLast) != kLast && (i0.y & kLast) != kLast && (i0.z & kLast) != kLast) {
        const Leaf* leaf = leaves.find(*level.index, nanovdb::Coord(i0.x, i0.y, i0.z));
        if (!leaf) return sum;
        const uint32_t first = Leaf::CoordToOffset(nanovdb::Coord(i0.x, i0.y, i0.z));
        for (int k = 0; k < 8; ++k)
            indices[k] = leaf->getValue(first + uint32_t((k & 1) << (2 * Leaf::LOG2DIM)) +
                                        uint32_t(((k >> 1) & 1) << Leaf::LOG2DIM) + uint32_t(k >> 2));
    } else {
        for (int k = 0; k < 8; ++k)
            indices[k] = leaves.value(*level.index, nanovdb::Coord(i0.x + (k & 1), i0.y + ((k >> 1) & 1), i0.z + (k >> 2)));
    }

    int travelFaces[3];
    float travelWeights[3];
    viewFaces(dir, travelFaces, travelWeights);
    const vec3 fromViewpoint = viewpoint ? base - *viewpoint : vec3(0.0f);
    for (int k = 0; k < 8; ++k) {
        if (indices[k] < 0) continue;
        const int dx = k & 1, dy = (k >> 1) & 1, dz = k >> 2;
        const float w = (dx ? f.x : 1.0f - f.x) * (dy ? f.y : 1.0f - f.y) * (dz ? f.z : 1.0f - f.z);
        if (w == 0.0f) continue;
        int faces[3] = {travelFaces[0], travelFaces[1], travelFaces[2]};
        float faceWeights[3] = {travelWeights[0], travelWeights[1], travelWeights[2]};
        if (viewpoint) {
            const vec3 u = fromViewpoint + vec3(float(dx), float(dy), float(dz));
            if (glm::dot(u, u) > 0.0f) viewFaces(u, faces, faceWeights);
        }
        const MipTexel* texels = level.texels + size_t(indices[k]) * size_t(level.facesPerVoxel);
        for (int a = 0; a < 3; ++a) {
            const MipTexel& t = texels[faces[a]];
            const float tw = w * faceWeights[a];
            sum.radiance += tw * t.radiance;
            sum.alpha += tw * t.alpha;
            sum.density += tw * t.density;
            sum.coverage += tw * t.coverage;
        }
    }
    return sum;
}

VL_HOSTDEV inline MipSample sampleMipLevel(const MipLevelView& level, const vec3& x, const vec3& dir,
                                           const vec3* viewpoint = nullptr) {
    IndexLeafCache leaves;
    return sampleMipLevel(level, leaves, x, dir, viewpoint);
}

// What one segment of `stepLength` (metres) around world point p contributes at fractional
// level λ (clamped to the chain), travelling along dir: (c', a') with
//   a' = 1 − exp(−σ · stepLength / (h·2^l)),  c' = (c / coverage) · a'
// (c / coverage = c / α where every texel is all surface; MipSample::colour) at each of the
// two nearest levels l, then linear in λ between them. For a single voxel sampled at its
// centre, 1 − exp(−σ·s/v) = 1 − (1 − α)^(s/v): the step-length correction.
// Correcting each level before blending keeps a uniform medium exact at any λ.
// `apex`, when given, is the viewer every voxel is seen from (sampleMipLevel).
// `leaves`, when given, holds one IndexLeafCache per level that persists along a cone.
VL_HOSTDEV inline vec4 coneSegment(const MipView& mips, const vec3& p, const vec3& dir, float level,
                                   float stepLength, const vec3* apex = nullptr, IndexLeafCache* leaves = nullptr) {
    if (mips.levelCount <= 0) return vec4(0.0f);
    level = glm::clamp(level, 0.0f, float(mips.levelCount - 1));
    const int lower = static_cast<int>(level);
    const float blend = level - float(lower);
    vec4 result(0.0f);
    for (int l = lower; l <= lower + 1 && l < mips.levelCount; ++l) {
        const float weight = l == lower ? 1.0f - blend : blend;
        if (weight <= 0.0f) continue;
        const MipLevelView& view = mips.levels[l];
        const vec3 viewpoint = apex ? *apex * view.inverseVoxelSize - vec3(view.centreOffset) : vec3(0.0f);
        IndexLeafCache local;
        const MipSample s = sampleMipLevel(view, leaves ? leaves[l] : local, p * view.inverseVoxelSize - vec3(view.centreOffset),
                                           dir, apex ? &viewpoint : nullptr);
        if (!(s.alpha > 0.0f)) continue;
        const float opacity = -expm1f(-s.density * stepLength * view.inverseVoxelSize);
        result += weight * vec4(s.colour() * opacity, opacity);
    }
    return result;
}

// Ray–box slab test; false when the ray misses. t may be negative (box behind or around o).
VL_HOSTDEV inline bool rayBoxInterval(const vec3& o, const vec3& d, const vec3& lo, const vec3& hi, float& tIn,
                                      float& tOut) {
    tIn = -kInfinity;
    tOut = kInfinity;
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0f) {
            if (o[a] < lo[a] || o[a] > hi[a]) return false;
            continue;
        }
        const float inv = 1.0f / d[a];
        float t0 = (lo[a] - o[a]) * inv, t1 = (hi[a] - o[a]) * inv;
        if (t0 > t1) {
            const float tmp = t0;
            t0 = t1;
            t1 = tmp;
        }
        tIn = glm::max(tIn, t0);
        tOut = glm::min(tOut, t1);
    }
    return tIn <= tOut;
}

// The receiver a cone leaves: the height of the apex above the receiver's tangent plane
// (metres) and the cosine between the cone axis and the receiver's normal. A cone's footprint
// must not reach below that plane, where the receiver's own surface voxels lie: a grazing
// cone wide enough to touch them would gather the receiver's own radiance (a floor lighting
// itself). The default (infinite height) is a cone with no receiver plane.
struct ConeOrigin {
    float apexHeight = kInfinity;
    float cosToNormal = 1.0f;
};

// One cone, apex o, unit axis d, half-angle θ:
//   diameter D(t) = max(h, 2 t tan θ) at distance t from the apex;
//   segment [t, t + s] with s = stepFactor·D(t), sampled at its midpoint tm, trilinearly in
//   the one level l nearest to λ = log2(D(tm)/h) − 1 (λ rounded, clamped to the chain). Why
//   −1: a trilinear sample spreads over two voxels, so level log2(D/h) blurs over twice the
//   cone's width, and wide cones see a closed box's coarse border voxels as partly empty.
//   Why one level and not the blend of the two around λ: half the reads, a lower error and
//   fewer leaks (docs/decisions.md, "Cone marching"). With stepFactor ≤ ½ the step is
//   at most 2^(λ−l) ≤ √2 voxels of the sampled level, and trilinear tents sampled that far
//   apart still sum to ≥ 2 − √2 of a wall's optical depth: a solid wall one voxel thick
//   passes at most e^(−0.59·6.9) ≈ 2% of what lies behind it (the leak test bounds it);
//   opacity corrected for the segment length: a' = 1 − (1 − a)^(s / (h·2^l)) per level l
//   (as 1 − exp(−σ s / (h·2^l)), see coneSegment), the premultiplied colour scaled by
//   a'/a; front to back: C += (1 − A)·c', A += (1 − A)·a'.
//   The cone stops at A ≥ 0.99, at maxDistance, or once it is outside the grid: past the
//   axis's exit from the level-0 bounds by more than the support of the sampled level
//   (1.5 of its voxels: a coarse border voxel's centre lies up to half a voxel outside, its
//   trilinear weight reaches one voxel beyond; stopping at the bounds themselves drops half
//   of every border wall's filtered opacity). A cone whose axis misses the bounds gathers
//   nothing.
// In a uniform medium of per-voxel opacity α this is Beer–Lambert at every level:
// T = (1 − α)^(distance/h) (radiance_mips.h: the directional texels compose α along axes).
// One cone; `dir` unit, tanHalfAngle > 0, maxDistance in metres (≤ 0: none).
VL_HOSTDEV inline ConeResult traceCone(const MipView& mips, const vec3& apex, const vec3& dir, float tanHalfAngle,
                                       float stepFactor, float maxDistance, const ConeOrigin& origin = ConeOrigin()) {
    constexpr float kOpaque = 0.99f;
    ConeResult result;
    if (mips.levelCount <= 0 || !isFinite(apex) || !isFinite(dir)) return result;
    float tIn, tOut;
    if (!rayBoxInterval(apex, dir, mips.boundsMin, mips.boundsMax, tIn, tOut) || tOut < 0.0f) return result;

    const float h = mips.voxelSize;
    const float maxLevel = float(mips.levelCount - 1);
    const float coarsestVoxel = mips.levels[mips.levelCount - 1].voxelSize;
    stepFactor = glm::max(stepFactor, 1.0e-3f);  // guarantees progress whatever the caller passes
    const float tEnd = maxDistance > 0.0f ? maxDistance : kInfinity;
    IndexLeafCache leaves[MipView::kMaxLevels];
    // Samples farther than a coarsest voxel and a half from the bounds read only zeros.
    float t = glm::max(0.0f, tIn - 1.5f * coarsestVoxel);
    while (t < tEnd && result.occlusion < kOpaque) {
        // A level-l sample reads voxel centres up to one level-l voxel away, and a level-l
        // voxel that holds the receiver's surface has its centre up to half of one above it:
        // the coarsest level a sample at height z may read is log2(z / 1.5h). The level is
        // rounded, up by at most ½, so λ stays one below that: λ_plane = log2(z / 3h) (kept
        // from when a fractional level read the next coarser one too; it leaves half a level
        // to spare). The step follows the footprint,
        // h·2^(max(λ_plane, 0) + 1) = max(2h, z / 1.5), so a clamped (finer) sample never
        // steps over a wall one of its voxels thick. Heights only grow along the cone, so the
        // bound taken at the step's start holds over the whole step.
        const float height = glm::max(origin.apexHeight + t * origin.cosToNormal, h);
        const float planeDiameter = glm::max(2.0f * h, height * (1.0f / 1.5f));
        const float step =
            glm::min(stepFactor * glm::max(h, glm::min(2.0f * t * tanHalfAngle, planeDiameter)), tEnd - t);
        const float tMid = t + 0.5f * step;
        const float diameter = glm::max(h, 2.0f * tMid * tanHalfAngle);
        // The level nearest to min(log2(D/h) − kConeLevelOffset, λ_plane), one logarithm.
        const float level = glm::floor(
            glm::clamp(glm::log2(glm::min(diameter * kConeLevelScale, height * (1.0f / 3.0f)) / h), 0.0f, maxLevel) +
            0.5f);
        // Past the bounds, coarse samples still read the blurred border voxels: their centres
        // lie up to half a voxel outside and trilinear weights reach one voxel further.
        if (tMid > tOut + 1.5f * mips.levels[static_cast<int>(level)].voxelSize) break;
        const vec4 segment = coneSegment(mips, apex + tMid * dir, dir, level, step, &apex, leaves);
        const float remaining = 1.0f - result.occlusion;
        result.radiance += remaining * vec3(segment);
        result.occlusion = glm::min(1.0f, result.occlusion + remaining * segment.w);
        t += step;
    }
    return result;
}

VL_HOSTDEV inline float coneHalfAngle(const ConeSet& set, const ConeSettings& settings) {
    return settings.apertureDegrees > 0.0f ? glm::radians(settings.apertureDegrees) : set.defaultHalfAngle;
}

// Where the cones of a point p with unit normal n start: settings.startOffset voxels of size h
// along n (what a gather by cones sees from; the bright patches and tools start there too).
VL_HOSTDEV inline vec3 coneApex(const vec3& p, const vec3& n, const ConeSettings& settings, float h) {
    return p + n * (settings.startOffset * h);
}

// Irradiance E at point p with normal n: π Σ_k w_k L_k over the set's cones around n, all
// starting settings.startOffset voxels along n (coneApex). A zero or non-finite n or p gives zero.
// `occlusion`, if given, receives Σ_k w_k A_k (cosine-weighted ambient occlusion).
// `turn` (in turns, [0, 1)) rotates the set about n. Why: a fixed set sees a small bright
// region (a light's hot spot on the ceiling) fully when a cone points at it and barely
// between cones, so every receiver with the same frame makes the same mistake and the errors
// form blotches. Receivers that turn their sets differently (coneTurn) make independent
// mistakes, which the mips average away (bounces) or a pixel's sub-samples average.
// `tangent`, when given (unit, orthogonal to n), is the frame's first axis before the turn;
// else orthonormalBasis picks one from n alone.
VL_HOSTDEV inline vec3 coneTraceIrradiance(const MipView& mips, const vec3& p, const vec3& n, const ConeSet& set,
                                           const ConeSettings& settings, float* occlusion = nullptr,
                                           float turn = 0.0f, const vec3* frameTangent = nullptr) {
    if (occlusion) *occlusion = 0.0f;
    const float length = glm::length(n);
    if (!(length > 1.0e-6f) || !isFinite(length) || !isFinite(p)) return vec3(0.0f);
    const vec3 normal = n / length;
    vec3 tangent, bitangent;
    if (frameTangent) {
        tangent = *frameTangent;
        bitangent = glm::cross(normal, tangent);
    } else {
        orthonormalBasis(normal, tangent, bitangent);
    }
    if (turn != 0.0f) {
        const float angle = 2.0f * kPi * turn;
        const float c = cosf(angle), s = sinf(angle);
        const vec3 turned = c * tangent + s * bitangent;
        bitangent = glm::cross(normal, turned);
        tangent = turned;
    }
    const float tanHalfAngle = glm::tan(coneHalfAngle(set, settings));
    const vec3 apex = coneApex(p, normal, settings, mips.voxelSize);
    vec3 sum(0.0f);
    float occluded = 0.0f;
    for (int k = 0; k < set.count; ++k) {
        const vec3& d = set.directions[k];
        const vec3 dir = glm::normalize(d.x * tangent + d.y * bitangent + d.z * normal);
        ConeOrigin origin;
        origin.apexHeight = settings.startOffset * mips.voxelSize;
        origin.cosToNormal = d.z;
        const ConeResult cone =
            traceCone(mips, apex, dir, tanHalfAngle, settings.stepFactor, settings.maxDistance, origin);
        sum += set.weights[k] * cone.radiance;
        occluded += set.weights[k] * cone.occlusion;
    }
    if (occlusion) *occlusion = occluded;
    return kPi * sum;
}

// A receiver's turn of the cone set: a hash of its index, uniform in [0, 1), the same at
// any thread count.
VL_HOSTDEV inline float coneTurn(uint64_t receiverIndex) {
    return float(splitMix64(receiverIndex) >> 40) * 0x1.0p-24f;
}

}  // namespace vl
