#include "gather/texel_gather.h"

#include "gather/fan_rays.h"
#include "gather/ray_gather.h"
#include "gather/shade_element.h"
#include "core/rng.h"
#include "trace/ray_offset.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cmath>

namespace vl {

namespace {

// A record may give light to a sample this many lattice spacings away (in the texels' size in
// the scene) and be of its surface: the window's diagonal is √2 spacings, and charts stretch.
constexpr float kRecordReach = 2.0f;
// Cosine between a sample's normal and a record's, below which they are not one surface.
constexpr float kRecordFacing = 0.7f;
// The filter's luminance stop: records apart by more than this many standard deviations of
// their difference's noise are not averaged (SVGF's σ_l).
constexpr float kNoiseStops = 4.0f;
// The filter's normal stop: cos^k between two records' normals (SVGF's σ_n).
constexpr int kNormalPower = 32;
// Records about this many voxels apart by default: the light in shade changes within a voxel
// at creases and corners, and more records of fewer rays each, filtered, follow it closer for
// the same noise (docs/accuracy.md, "Records closer, of fewer rays").
constexpr float kRecordSpacingVoxels = 0.6f;
// Rays per axis of a record's fan by default: the filter averages a record with its neighbours,
// so past 8 × 8 rays a record buys little of the error.
constexpr int kAutoRecordRays = 8;

struct Record {
    SurfaceSample sample;
    size_t texel = 0;
    uint64_t seed = 0;
    vec3 ng{0.0f};  // geometric normal on the sample's side
    bool lit = false;     // a light or an emitter reaches it directly
    bool buried = false;
    vec3 indirect{0.0f};  // E
    vec3 sky{0.0f};       // E
    float variance = 0.0f;  // of the mean channel of indirect + sky
    RotationGradients rotation;  // of indirect (less the bright patches') and sky; zero without them
};

// A record's light turned to a sample's normal by its rotation gradients (ray_gather.h): a
// record's neighbours on a curved cushion or a moulding face a little away from it, and see
// more or less of what lies round them. Never below zero.
vec3 indirectAt(const Record& r, const vec3& normal) {
    return glm::max(r.indirect + r.rotation.light * (normal - r.sample.normal), vec3(0.0f));
}
vec3 skyAt(const Record& r, const vec3& normal) {
    return glm::max(r.sky + r.rotation.sky * (normal - r.sample.normal), vec3(0.0f));
}

// The sample of a texel that stands for it as a record: the one with the largest share.
const SurfaceSample* mainSample(const SurfaceSampleSet& set, size_t texel) {
    const SurfaceSample* best = nullptr;
    for (uint32_t k = set.begin[texel]; k < set.begin[texel + 1]; ++k)
        if (!best || set.samples[k].weight > best->weight) best = &set.samples[k];
    return best;
}

vec3 sideGeometricNormal(const TraceSceneView& scene, const SurfaceSample& s) {
    const vec3 ng = glm::normalize(windingCross(scene, s.triangle));
    return glm::dot(ng, s.normal) < 0.0f ? -ng : ng;
}

// The median distance in the scene between horizontally adjacent covered texels on one
// triangle: the texels' size.
float texelWorldSize(const LightmapAtlas& atlas) {
    const SurfaceSampleSet& set = atlas.receivers;
    std::vector<float> sizes;
    const size_t stride = std::max<size_t>(1, set.elementCount() / 200000);
    for (size_t e = 0; e + 1 < set.elementCount(); e += stride) {
        if ((e + 1) % size_t(set.width) == 0) continue;
        if (set.sampleCount(e) == 0 || set.sampleCount(e + 1) == 0) continue;
        const SurfaceSample* a = mainSample(set, e);
        const SurfaceSample* b = mainSample(set, e + 1);
        if (a->triangle != b->triangle) continue;
        sizes.push_back(glm::length(a->position - b->position));
    }
    if (sizes.empty()) return 0.0f;
    std::nth_element(sizes.begin(), sizes.begin() + std::ptrdiff_t(sizes.size() / 2), sizes.end());
    return sizes[sizes.size() / 2];
}

float meanOf(const vec3& v) { return (v.x + v.y + v.z) / 3.0f; }

// Gathers `records[first …]`: their fans (laid out from their triangle's first edge, turned by
// where their texel lies, the R2 sequence over x and y, so neighbours look between each other's
// rays), whether a light reaches them, whether they are buried, and their light.
void gatherRecords(std::vector<Record>& records, size_t first, int width, const MipView& mips,
                   const std::vector<FaceRadiance>& faces, const BrightPatchSplit& bright, const BvhView& bvh,
                   const TraceSceneView& scene, const TexelGatherSettings& settings) {
    const size_t count = records.size() - first;
    std::vector<FanStart> fans(count);
    DirectLightSettings direct = settings.direct;
    direct.skyAtSamples = false;
    tbb::parallel_for(size_t(0), count, [&](size_t k) {
        Record& r = records[first + k];
        r.ng = sideGeometricNormal(scene, r.sample);
        r.lit = maxComponent(directIrradiance(scene, bvh, r.sample, direct, r.seed)) > 0.0f;
        const vec3* corner = scene.vertices + 3 * size_t(r.sample.triangle);
        const vec3 edge = corner[1] - corner[0];
        vec3 tangent = edge - glm::dot(edge, r.sample.normal) * r.sample.normal, bitangent;
        if (glm::length(tangent) > 1e-12f) tangent = glm::normalize(tangent);
        else orthonormalBasis(r.sample.normal, tangent, bitangent);
        const double turn = double(r.texel % size_t(width)) * 0.7548776662466927 +
                            double(r.texel / size_t(width)) * 0.5698402909980532 + double(settings.seed) * 0.3819660112501051;
        fans[k].origin = offsetRayOrigin(r.sample.position, r.ng, bvh.extent);
        fans[k].frame = fanFrame(r.sample.normal, tangent, float(turn - std::floor(turn)));
        fans[k].seed = r.seed + settings.seed * 0x9E3779B97F4A7C15ull;
        Pcg32 rng(fans[k].seed, 0x7e7e1);
        rng.next2D(fans[k].jitter.x, fans[k].jitter.y);
    });
    FanExtras extras;
    extras.readSky = settings.gatherSky;
    extras.lightsAtHits = settings.lightsAtHits;
    extras.nearField = settings.nearField;
    extras.rotationGradients = settings.gradients;
    const std::vector<vec3> gathered =
        gatherFans(fans, mips, faces, bvh, scene, settings.raysPerAxis, nullptr, &extras, settings.skyDrawsPerAxis);
    tbb::parallel_for(size_t(0), count, [&](size_t k) {
        Record& r = records[first + k];
        r.buried = !r.lit && extras.escaped[k] == 0 && isBuried(scene, bvh, r.sample);
        if (r.buried) return;
        float brightVariance = 0.0f;
        r.indirect = gathered[k] + brightPatchIrradiance(bright, bvh, fans[k].origin, r.sample.normal,
                                                          settings.brightSamples, r.seed, &brightVariance);
        r.sky = extras.sky[k];
        r.variance = extras.variance[k] + brightVariance;
        if (settings.gradients) r.rotation = extras.rotation[k];
    });
}

}  // namespace

int texelGatherSpacing(const LightmapAtlas& atlas, float voxelSize, const TexelGatherSettings& settings) {
    if (settings.spacing > 0) return settings.spacing;
    const float size = texelWorldSize(atlas);
    if (!(size > 0.0f)) return 1;
    return std::clamp(int(std::lround(kRecordSpacingVoxels * voxelSize / size)), 1, 8);
}

int texelGatherRays(const TexelGatherSettings& settings) {
    return settings.raysPerAxis > 0 ? settings.raysPerAxis : kAutoRecordRays;
}

TexelGather gatherAtlasTexels(const LightmapAtlas& atlas, int rowBegin, int rowEnd, const Image* direct,
                              const MipView& mips, const std::vector<FaceRadiance>& faces, const BrightPatchSplit& bright,
                              const BvhView& bvh, const TraceSceneView& scene, const TexelGatherSettings& settings) {
    const SurfaceSampleSet& set = atlas.receivers;
    const int W = set.width, H = set.height;
    TexelGather out;
    out.indirect = Image(W, H, 3);
    out.sky = Image(W, H, 3);
    out.open = Image(W, H, 1);
    rowBegin = std::clamp(rowBegin, 0, H);
    rowEnd = std::clamp(rowEnd, rowBegin, H);
    if (rowBegin == rowEnd || mips.levelCount <= 0) return out;
    const int s = texelGatherSpacing(atlas, mips.voxelSize, settings);
    const float texelSize = std::max(texelWorldSize(atlas), 1e-6f);
    TexelGatherSettings gather = settings;
    gather.raysPerAxis = texelGatherRays(settings);
    const float reach = kRecordReach * float(s) * texelSize;
    const int half = s / 2;
    const auto compatible = [&](const SurfaceSample& a, const Record& r) {
        const vec3 d = a.position - r.sample.position;
        return glm::dot(d, d) <= reach * reach && glm::dot(a.normal, r.sample.normal) >= kRecordFacing &&
               glm::abs(glm::dot(d, r.sample.normal)) <= 0.5f * reach;
    };

    // The lattice: node (i, j) at texel (half + i·s, half + j·s). Its records cover the rows the
    // band's texels interpolate from and, past them, as far as the filter's passes read.
    const int passes = std::max(0, settings.filterPasses);
    // Lattice steps: a pass reads its neighbours 2 steps out and their sums of weights, 2 more.
    const int filterReach = passes > 0 ? 4 * ((1 << passes) - 1) : 0;
    const int columns = (W - half + s - 1) / s;
    const int jBegin = std::max(0, (rowBegin - half) / s - 1 - filterReach);
    const int jEnd = std::min((H - half + s - 1) / s, (rowEnd - half) / s + 2 + filterReach);
    const int rows = std::max(0, jEnd - jBegin);
    std::vector<int32_t> node(size_t(columns) * size_t(rows), -1);
    std::vector<Record> records;
    for (int j = jBegin; j < jEnd; ++j)
        for (int i = 0; i < columns; ++i) {
            const size_t texel = size_t(half + j * s) * size_t(W) + size_t(half + i * s);
            if (set.sampleCount(texel) == 0) continue;
            Record r;
            r.sample = *mainSample(set, texel);
            r.texel = texel;
            r.seed = texel;
            node[size_t(j - jBegin) * size_t(columns) + size_t(i)] = int32_t(records.size());
            records.push_back(r);
        }
    const size_t latticeRecords = records.size();
    gatherRecords(records, 0, W, mips, faces, bright, bvh, scene, gather);
    const auto nodeAt = [&](int i, int j) -> int32_t {
        if (i < 0 || i >= columns || j < jBegin || j >= jEnd) return -1;
        return node[size_t(j - jBegin) * size_t(columns) + size_t(i)];
    };

    // The edge-stopping filter over the lattice's records, pass p at a step of 2^p nodes, each
    // reading the 5 × 5 nodes of its step (the B3 spline's weights) that lie on the record's
    // surface and whose light their noise explains; the variance goes through as Σ a² σ².
    // The weight of two records in pass `step` at lattice offset (di, dj): the kernel's, times
    // how far they lie on one surface (within reach of their lattice distance, in each other's
    // plane, facing one way) and their difference against its noise, both records' variances.
    // The record's own variance alone let a lucky bright record (its spread large) take its
    // neighbours' light while an unlucky dark one (its spread small) refused theirs, and the
    // filter darkened the lightmap (docs/accuracy.md, "The filter's stop"). The same both ways.
    constexpr float kernel[3] = {3.0f / 8.0f, 1.0f / 4.0f, 1.0f / 16.0f};
    const auto pairWeight = [&](const Record& rp, const Record& rq, int di, int dj, int step) {
        const vec3 d = rq.sample.position - rp.sample.position;
        const float apart = (std::sqrt(float(di * di + dj * dj)) * float(step) + 1.0f) * reach;
        if (glm::dot(d, d) > apart * apart) return 0.0f;
        const float offPlane = std::max(glm::abs(glm::dot(d, rp.sample.normal)), glm::abs(glm::dot(d, rq.sample.normal)));
        if (offPlane > 0.25f * reach + 0.1f * glm::length(d)) return 0.0f;
        const float facing = glm::dot(rp.sample.normal, rq.sample.normal);
        if (!(facing > kRecordFacing)) return 0.0f;
        const float lp = meanOf(rp.indirect + rp.sky), lq = meanOf(rq.indirect + rq.sky);
        const float stop = kNoiseStops * std::sqrt(std::max(rp.variance, 0.0f) + std::max(rq.variance, 0.0f)) +
                           1e-6f * (std::max(lp, lq) + 1e-6f);
        return kernel[std::abs(di)] * kernel[std::abs(dj)] * std::pow(facing, float(kNormalPower)) *
               std::exp(-std::abs(lp - lq) / stop);
    };
    for (int pass = 0; pass < passes; ++pass) {
        const int step = 1 << pass;
        // Each record's sum of weights, itself included.
        std::vector<float> weightSum(latticeRecords, 0.0f);
        tbb::parallel_for(jBegin, jEnd, [&](int j) {
            for (int i = 0; i < columns; ++i) {
                const int32_t p = nodeAt(i, j);
                if (p < 0 || records[size_t(p)].buried) continue;
                float total = 0.0f;
                for (int dj = -2; dj <= 2; ++dj)
                    for (int di = -2; di <= 2; ++di) {
                        const int32_t q = nodeAt(i + di * step, j + dj * step);
                        if (q >= 0 && !records[size_t(q)].buried)
                            total += pairWeight(records[size_t(p)], records[size_t(q)], di, dj, step);
                    }
                weightSum[size_t(p)] = total;
            }
        });
        // A record takes w / max(W_p, W_q) of each neighbour's difference from it: the same
        // share both ways, so what one gains the other loses and the filter keeps the records'
        // sum (a bright record's wide spread accepts more neighbours, and normalising each by
        // its own sum W_p brightened the lightmap), and never more than W_p: a mean.
        std::vector<vec3> indirect(latticeRecords), sky(latticeRecords);
        std::vector<float> variance(latticeRecords);
        std::vector<RotationGradients> rotation(settings.gradients ? latticeRecords : 0);
        tbb::parallel_for(jBegin, jEnd, [&](int j) {
            for (int i = 0; i < columns; ++i) {
                const int32_t p = nodeAt(i, j);
                if (p < 0) continue;
                const Record& rp = records[size_t(p)];
                vec3 sumIndirect(0.0f), sumSky(0.0f);
                float taken = 0.0f, sumVariance = 0.0f;
                RotationGradients sumRotation;
                if (!rp.buried)
                    for (int dj = -2; dj <= 2; ++dj)
                        for (int di = -2; di <= 2; ++di) {
                            const int32_t q = nodeAt(i + di * step, j + dj * step);
                            if (q < 0 || q == p) continue;
                            const Record& rq = records[size_t(q)];
                            if (rq.buried) continue;
                            const float w = pairWeight(rp, rq, di, dj, step);
                            if (!(w > 0.0f)) continue;
                            const float share = w / std::max(weightSum[size_t(p)], weightSum[size_t(q)]);
                            sumIndirect += share * rq.indirect;
                            sumSky += share * rq.sky;
                            sumVariance += share * share * rq.variance;
                            sumRotation.light += share * rq.rotation.light;
                            sumRotation.sky += share * rq.rotation.sky;
                            taken += share;
                        }
                const float own = 1.0f - taken;
                indirect[size_t(p)] = own * rp.indirect + sumIndirect;
                sky[size_t(p)] = own * rp.sky + sumSky;
                variance[size_t(p)] = own * own * rp.variance + sumVariance;
                if (settings.gradients)
                    rotation[size_t(p)] = {own * rp.rotation.light + sumRotation.light, own * rp.rotation.sky + sumRotation.sky};
            }
        });
        for (size_t k = 0; k < latticeRecords; ++k) {
            records[k].indirect = indirect[k];
            records[k].sky = sky[k];
            records[k].variance = variance[k];
            if (settings.gradients) records[k].rotation = rotation[k];
        }
    }

    // The lattice records around texel (x, y) on a sample's surface (the nodes at or before x
    // and y and the next ones) with their bilinear weights; whether one of them is buried.
    struct Around {
        int32_t slot[4];
        float weight[4];
        bool buriedNear;
    };
    const auto around = [&](int x, int y, const SurfaceSample& sample) {
        Around a;
        a.buriedNear = false;
        const int i0 = int(std::floor(float(x - half) / float(s))), j0 = int(std::floor(float(y - half) / float(s)));
        for (int dj = 0; dj < 2; ++dj)
            for (int di = 0; di < 2; ++di) {
                const int k = 2 * dj + di;
                a.slot[k] = -1;
                a.weight[k] = 0.0f;
                const int32_t slot = nodeAt(i0 + di, j0 + dj);
                if (slot < 0 || !compatible(sample, records[size_t(slot)])) continue;
                if (records[size_t(slot)].buried) {
                    a.buriedNear = true;
                    continue;
                }
                a.slot[k] = slot;
                a.weight[k] = (1.0f - float(std::abs(x - (half + (i0 + di) * s))) / float(s)) *
                              (1.0f - float(std::abs(y - (half + (j0 + dj) * s))) / float(s));
            }
        return a;
    };
    const auto anyWeight = [](const Around& a) {
        return a.weight[0] > 0.0f || a.weight[1] > 0.0f || a.weight[2] > 0.0f || a.weight[3] > 0.0f;
    };

    // Samples no lattice record applies to share records of their own, one per s × s block of
    // the atlas and surface: each block is scanned whole, in texel order, so a block's records
    // do not depend on the band.
    const int blockBegin = rowBegin / s, blockEnd = (rowEnd + s - 1) / s;
    const int blocksAcross = (W + s - 1) / s;
    std::vector<std::vector<Record>> blockRecords(size_t(blockEnd - blockBegin) * size_t(blocksAcross));
    struct BlockUse {
        uint32_t sample;
        uint32_t record;  // in the block's own records until they join `records`, then in `records`
        size_t texel;
    };
    std::vector<std::vector<BlockUse>> blockUse(blockRecords.size());  // in sample order
    tbb::parallel_for(size_t(0), blockRecords.size(), [&](size_t b) {
        const int bx = int(b % size_t(blocksAcross)), by = blockBegin + int(b / size_t(blocksAcross));
        std::vector<Record>& own = blockRecords[b];
        for (int y = by * s; y < std::min(H, (by + 1) * s); ++y)
            for (int x = bx * s; x < std::min(W, (bx + 1) * s); ++x) {
                const size_t texel = size_t(y) * size_t(W) + size_t(x);
                for (uint32_t k = set.begin[texel]; k < set.begin[texel + 1]; ++k) {
                    if (anyWeight(around(x, y, set.samples[k]))) continue;
                    uint32_t use = uint32_t(own.size());
                    for (uint32_t r = 0; r < own.size() && use == own.size(); ++r)
                        if (compatible(set.samples[k], own[r])) use = r;
                    if (use == own.size()) {
                        Record r;
                        r.sample = set.samples[k];
                        r.texel = texel;
                        r.seed = (uint64_t(1) << 40) | k;
                        own.push_back(r);
                    }
                    blockUse[b].push_back({k, use, texel});
                }
            }
    });
    for (size_t b = 0; b < blockRecords.size(); ++b) {
        const uint32_t first = uint32_t(records.size());
        for (BlockUse& use : blockUse[b]) use.record += first;
        records.insert(records.end(), blockRecords[b].begin(), blockRecords[b].end());
    }
    gatherRecords(records, latticeRecords, W, mips, faces, bright, bvh, scene, gather);

    // A block's record may be buried where some samples sharing it are not (a wall's texels
    // beside the foot of a panel hung on it): those take records of their own, shared as before.
    std::vector<std::vector<Record>> reopened(blockRecords.size());
    std::vector<std::vector<std::pair<size_t, uint32_t>>> reopenedUse(blockRecords.size());  // (use, record)
    tbb::parallel_for(size_t(0), blockRecords.size(), [&](size_t b) {
        for (size_t u = 0; u < blockUse[b].size(); ++u) {
            const BlockUse& use = blockUse[b][u];
            if (!records[use.record].buried) continue;
            const SurfaceSample& sample = set.samples[use.sample];
            const bool lit = direct && maxComponent(direct->rgb(int(use.texel % size_t(W)), int(use.texel / size_t(W)))) > 0.0f;
            if (!lit && isBuried(scene, bvh, sample)) continue;
            std::vector<Record>& own = reopened[b];
            uint32_t r = 0;
            while (r < own.size() && !compatible(sample, own[r])) ++r;
            if (r == own.size()) {
                Record record;
                record.sample = sample;
                record.texel = use.texel;
                record.seed = (uint64_t(2) << 40) | use.sample;
                own.push_back(record);
            }
            reopenedUse[b].emplace_back(u, r);
        }
    });
    const size_t firstReopened = records.size();
    for (size_t b = 0; b < blockRecords.size(); ++b) {
        const uint32_t first = uint32_t(records.size());
        for (const auto& [u, r] : reopenedUse[b]) blockUse[b][u].record = first + r;
        records.insert(records.end(), reopened[b].begin(), reopened[b].end());
    }
    if (records.size() > firstReopened) gatherRecords(records, firstReopened, W, mips, faces, bright, bvh, scene, gather);

    // Each sample: its lattice records, bilinearly, else its block's record.
    tbb::parallel_for(rowBegin, rowEnd, [&](int y) {
        const int by = y / s - blockBegin;
        for (int x = 0; x < W; ++x) {
            const size_t texel = size_t(y) * size_t(W) + size_t(x);
            if (set.sampleCount(texel) == 0) continue;
            const size_t b = size_t(by) * size_t(blocksAcross) + size_t(x / s);
            vec3 indirect(0.0f), sky(0.0f);
            float open = 0.0f;
            for (uint32_t k = set.begin[texel]; k < set.begin[texel + 1]; ++k) {
                const SurfaceSample& sample = set.samples[k];
                const Around a = around(x, y, sample);
                vec3 Ei(0.0f), Es(0.0f);
                bool buried = false;
                if (anyWeight(a)) {
                    float total = 0.0f;
                    for (int c = 0; c < 4; ++c)
                        if (a.weight[c] > 0.0f) {
                            const Record& r = records[size_t(a.slot[c])];
                            Ei += a.weight[c] * indirectAt(r, sample.normal);
                            Es += a.weight[c] * skyAt(r, sample.normal);
                            total += a.weight[c];
                        }
                    Ei /= total;
                    Es /= total;
                    // Beside closed geometry (a floor at a block's foot) the sample may be inside it.
                    buried = a.buriedNear && !(direct && maxComponent(direct->rgb(x, y)) > 0.0f) &&
                             isBuried(scene, bvh, sample);
                    if (buried) Ei = Es = vec3(0.0f);
                } else {
                    const auto& uses = blockUse[b];
                    const auto use = std::lower_bound(uses.begin(), uses.end(), k,
                                                      [](const BlockUse& u, uint32_t sample) { return u.sample < sample; });
                    if (use != uses.end() && use->sample == k) {
                        const Record& r = records[use->record];
                        buried = r.buried;
                        Ei = indirectAt(r, sample.normal);
                        Es = skyAt(r, sample.normal);
                    }
                }
                indirect += sample.weight * Ei;
                sky += sample.weight * Es;
                if (!buried) open += sample.weight;
            }
            out.indirect.setRgb(x, y, indirect * kInvPi);
            out.sky.setRgb(x, y, sky * kInvPi);
            out.open.at(x, y) = open;
        }
    });
    return out;
}

}  // namespace vl
