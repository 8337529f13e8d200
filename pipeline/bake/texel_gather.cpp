#include "bake/texel_gather.h"

#include "bake/fan_rays.h"
#include "bake/ray_gather.h"
#include "bake/shade_element.h"
#include "core/progress.h"
#include "trace/ray_offset.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace vl {

namespace {

// A record may lie this many lattice spacings (in the texels' size in the scene) from a sample
// it gives light to: the window's diagonal is √2 spacings, and charts stretch a little.
constexpr float kRecordReach = 2.0f;
// Cosine between a sample's normal and a record's, below which they are not one surface.
constexpr float kRecordFacing = 0.7f;

struct Record {
    SurfaceSample sample;
    size_t texel = 0;
    uint64_t seed = 0;
    vec3 ng{0.0f};  // geometric normal on the sample's side
    bool buried = false;
    vec3 irradiance{0.0f};
};

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

}  // namespace

int texelGatherSpacing(const LightmapAtlas& atlas, float voxelSize, const TexelGatherSettings& settings) {
    if (settings.spacing > 0) return settings.spacing;
    const float size = texelWorldSize(atlas);
    if (!(size > 0.0f)) return 1;
    return std::clamp(int(std::lround(1.5f * voxelSize / size)), 1, 8);
}

Image gatherAtlasIndirect(const LightmapAtlas& atlas, int rowBegin, int rowEnd, const Image* direct,
                          const MipView& mips, const std::vector<FaceRadiance>& faces, const BrightPatchSplit& bright,
                          const BvhView& bvh, const TraceSceneView& scene, const TexelGatherSettings& settings) {
    const SurfaceSampleSet& set = atlas.receivers;
    const int W = set.width, H = set.height;
    Image out(W, H, 3);
    rowBegin = std::clamp(rowBegin, 0, H);
    rowEnd = std::clamp(rowEnd, rowBegin, H);
    if (rowBegin == rowEnd || mips.levelCount <= 0) return out;
    const int s = texelGatherSpacing(atlas, mips.voxelSize, settings);
    const float texelSize = std::max(texelWorldSize(atlas), 1e-6f);
    const float reach = kRecordReach * float(s) * texelSize;
    const int half = s / 2;
    const auto compatible = [&](const SurfaceSample& a, const Record& r) {
        const vec3 d = a.position - r.sample.position;
        return glm::dot(d, d) <= reach * reach && glm::dot(a.normal, r.sample.normal) >= kRecordFacing &&
               glm::abs(glm::dot(d, r.sample.normal)) <= 0.5f * reach;
    };
    // A texel with direct light is open to it: not buried (shade_element.h isBuried's rule).
    const auto mayBeBuried = [&](size_t texel) {
        if (!direct) return true;
        const int x = int(texel % size_t(W)), y = int(texel / size_t(W));
        return !(maxComponent(direct->rgb(x, y)) > 0.0f);
    };
    const auto prepare = [&](std::vector<Record>& records, size_t first) {
        tbb::parallel_for(first, records.size(), [&](size_t k) {
            Record& r = records[k];
            r.ng = sideGeometricNormal(scene, r.sample);
            r.buried = mayBeBuried(r.texel) && isBuried(scene, bvh, r.sample);
        });
    };

    // The lattice's records, over the rows the band's texels interpolate from.
    const int firstRow = std::max(0, rowBegin - s), lastRow = std::min(H, rowEnd + s);
    std::vector<int32_t> latticeSlot(size_t(W) * size_t(lastRow - firstRow), -1);
    std::vector<Record> records;
    for (int y = firstRow; y < lastRow; ++y) {
        if (y % s != half) continue;
        for (int x = half; x < W; x += s) {
            const size_t texel = size_t(y) * size_t(W) + size_t(x);
            if (set.sampleCount(texel) == 0) continue;
            Record r;
            r.sample = *mainSample(set, texel);
            r.texel = texel;
            r.seed = texel;
            latticeSlot[size_t(y - firstRow) * size_t(W) + size_t(x)] = int32_t(records.size());
            records.push_back(r);
        }
    }
    const size_t latticeRecords = records.size();
    prepare(records, 0);

    // The lattice records around texel (x, y), the lattice points at or before x and y and the
    // next ones, with their bilinear weights; those not on the sample's surface, or buried,
    // weigh nothing.
    struct Around {
        int32_t slot[4];
        float weight[4];
        bool buriedNear;  // a record on the sample's surface around it is buried
    };
    const auto around = [&](int x, int y, const SurfaceSample& sample) {
        Around a;
        a.buriedNear = false;
        const int x0 = int(std::floor(float(x - half) / float(s))) * s + half;
        const int y0 = int(std::floor(float(y - half) / float(s))) * s + half;
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i) {
                const int lx = x0 + i * s, ly = y0 + j * s, k = 2 * j + i;
                a.slot[k] = -1;
                a.weight[k] = 0.0f;
                if (lx < 0 || lx >= W || ly < firstRow || ly >= lastRow) continue;
                const int32_t slot = latticeSlot[size_t(ly - firstRow) * size_t(W) + size_t(lx)];
                if (slot < 0 || !compatible(sample, records[size_t(slot)])) continue;
                if (records[size_t(slot)].buried) {
                    a.buriedNear = true;
                    continue;
                }
                a.slot[k] = slot;
                a.weight[k] = (1.0f - float(std::abs(x - lx)) / float(s)) * (1.0f - float(std::abs(y - ly)) / float(s));
            }
        return a;
    };
    const auto anyWeight = [](const Around& a) {
        return a.weight[0] > 0.0f || a.weight[1] > 0.0f || a.weight[2] > 0.0f || a.weight[3] > 0.0f;
    };

    // Samples no lattice record applies to (a chart narrower than the lattice, a chart's
    // corner, beside closed geometry) share records of their own, one per s × s block of the
    // atlas and surface: each block is scanned whole, in texel order, so a block's records do
    // not depend on the band.
    const int blockBegin = rowBegin / s, blockEnd = (rowEnd + s - 1) / s;
    const int blocksAcross = (W + s - 1) / s;
    std::vector<std::vector<Record>> blockRecords(size_t(blockEnd - blockBegin) * size_t(blocksAcross));
    std::vector<std::vector<std::pair<uint32_t, uint32_t>>> blockUse(blockRecords.size());  // (sample, record in block)
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
                    blockUse[b].emplace_back(k, use);
                }
            }
    });
    std::vector<size_t> blockFirst(blockRecords.size() + 1, 0);
    for (size_t b = 0; b < blockRecords.size(); ++b) {
        blockFirst[b] = records.size();
        records.insert(records.end(), blockRecords[b].begin(), blockRecords[b].end());
    }
    prepare(records, latticeRecords);

    // Each record's fan, turned by where its texel lies (the R2 sequence over x and y), so
    // neighbouring records look between each other's rays.
    std::vector<FanStart> fans(records.size());
    tbb::parallel_for(size_t(0), records.size(), [&](size_t k) {
        const Record& r = records[k];
        // Laid out from the sample's triangle's first edge, which turns with the scene.
        const vec3* corner = scene.vertices + 3 * size_t(r.sample.triangle);
        const vec3 edge = corner[1] - corner[0];
        vec3 tangent = edge - glm::dot(edge, r.sample.normal) * r.sample.normal, bitangent;
        if (glm::length(tangent) > 1e-12f) tangent = glm::normalize(tangent);
        else orthonormalBasis(r.sample.normal, tangent, bitangent);
        const double turn = double(r.texel % size_t(W)) * 0.7548776662466927 + double(r.texel / size_t(W)) * 0.5698402909980532;
        fans[k].origin = offsetRayOrigin(r.sample.position, r.ng, bvh.extent);
        fans[k].frame = fanFrame(r.sample.normal, tangent, float(turn - std::floor(turn)));
    });
    const std::vector<vec3> gathered = gatherFans(fans, mips, faces, bvh, scene, settings.raysPerAxis);
    tbb::parallel_for(size_t(0), records.size(), [&](size_t k) {
        Record& r = records[k];
        if (!r.buried)
            r.irradiance =
                gathered[k] + brightPatchIrradiance(bright, bvh, fans[k].origin, r.sample.normal, settings.brightSamples, r.seed);
    });

    // Each sample: its lattice records, bilinearly, else its block's record.
    tbb::parallel_for(rowBegin, rowEnd, [&](int y) {
        const int by = y / s - blockBegin;
        for (int x = 0; x < W; ++x) {
            const size_t texel = size_t(y) * size_t(W) + size_t(x);
            if (set.sampleCount(texel) == 0) continue;
            const size_t b = size_t(by) * size_t(blocksAcross) + size_t(x / s);
            vec3 texelValue(0.0f);
            for (uint32_t k = set.begin[texel]; k < set.begin[texel + 1]; ++k) {
                const Around a = around(x, y, set.samples[k]);
                vec3 E(0.0f);
                if (anyWeight(a)) {
                    float total = 0.0f;
                    for (int c = 0; c < 4; ++c)
                        if (a.weight[c] > 0.0f) {
                            E += a.weight[c] * records[size_t(a.slot[c])].irradiance;
                            total += a.weight[c];
                        }
                    E /= total;
                    // Beside closed geometry (a floor at a block's foot) it may be inside it.
                    if (a.buriedNear && mayBeBuried(texel) && isBuried(scene, bvh, set.samples[k])) E = vec3(0.0f);
                } else {
                    const auto& uses = blockUse[b];
                    const auto use = std::lower_bound(uses.begin(), uses.end(), std::make_pair(k, uint32_t(0)));
                    if (use != uses.end() && use->first == k) E = records[blockFirst[b] + use->second].irradiance;
                }
                texelValue += set.samples[k].weight * E;
            }
            out.setRgb(x, y, texelValue * kInvPi);
        }
    });
    return out;
}

}  // namespace vl
