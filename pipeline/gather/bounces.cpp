#include "gather/bounces.h"

#include "core/error.h"
#include "core/progress.h"
#include "gather/gather_scene.h"
#include "gather/irradiance_cache.h"
#include "gather/ray_gather.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <string>
#include <utility>

namespace vl {

namespace {

constexpr int kMaxBounces = 1024;
// A ratio near 1 (a closed white room) would blow the tail up from a noisy estimate: its tail
// is capped at 19 times the last bounce.
constexpr double kMaxTailRatio = 0.95;

void checkChannels(const VoxelScene& voxels) {
    const size_t n = voxels.size();
    const auto check = [&](size_t size, const char* name) {
        if (size != n)
            throw Error("propagateBounces(" + voxels.sourceScene + "): " + name + " has " + std::to_string(size) +
                        " values for " + std::to_string(n) + " voxels");
    };
    check(voxels.radiance.size(), "radiance");
    if (!voxels.faceRadiance.empty()) check(voxels.faceRadiance.size(), "faceRadiance");
    check(voxels.albedo.size(), "albedo");
    check(voxels.normal.size(), "normal");
    check(voxels.axisWeights.size(), "axisWeights");
}

// The lit faces: faceRadiance, or `radiance` on every face with a surface.
std::vector<FaceRadiance> litFaces(const VoxelScene& voxels) {
    if (!voxels.faceRadiance.empty()) return voxels.faceRadiance;
    std::vector<FaceRadiance> faces(voxels.size());
    tbb::parallel_for(size_t(0), voxels.size(), [&](size_t i) {
        for (size_t f = 0; f < 6; ++f) faces[i][f] = voxels.axisWeights[i][f] > 0.0f ? voxels.radiance[i] : vec3(0.0f);
    });
    return faces;
}

std::vector<vec3> isotropic(const VoxelScene& voxels, const std::vector<FaceRadiance>& faces) {
    std::vector<vec3> radiance(faces.size());
    tbb::parallel_for(size_t(0), faces.size(), [&](size_t i) {
        radiance[i] = faceWeightedMean(faces[i].data(), voxels.axisWeights[i].data());
    });
    return radiance;
}

// How much light one bounce added: Σ over faces of axis weight × (r + g + b) of the new light
// less the old, summed in fixed chunks, each in order, and the chunks in order: the same
// double at any thread count (the tail's ratio, and so the bake's bytes, depend on it).
constexpr size_t kAddedChunkVoxels = 4096;

// A voxel's faces' sides (VoxelSides::sideOfFace, −1: no surface) and how many.
struct FaceSides {
    std::array<int8_t, 6> side;
    int8_t count;
};

// Which gather points each voxel side reads and how much (visitCachePoints), computed once:
// the points and the voxels do not move between bounces. Sides no point applies to gather
// at the voxel itself (`selfGathered`).
struct SideWeights {
    std::vector<uint32_t> begin;  // per voxel side slot (voxel·6 + side): [begin[s], begin[s + 1])
    std::vector<uint32_t> point;
    std::vector<float> weight;    // normalised: Σ = 1 per side
    std::vector<uint32_t> selfGathered;  // side slots with no point
};

// The value at voxel side `slot` from per-point values: its gather points' weighted sum, or,
// for a side no point applies to, its own point's (self[k] for the k-th self-gathered side).
template <typename Value, typename AtPoint, typename AtSelf>
Value sideValue(const SideWeights& weights, size_t slot, AtPoint&& atPoint, AtSelf&& atSelf) {
    if (weights.begin[slot] == weights.begin[slot + 1]) {
        const auto found =
            std::lower_bound(weights.selfGathered.begin(), weights.selfGathered.end(), static_cast<uint32_t>(slot));
        return atSelf(size_t(found - weights.selfGathered.begin()));
    }
    Value sum(0.0f);
    for (uint32_t k = weights.begin[slot]; k < weights.begin[slot + 1]; ++k) sum += weights.weight[k] * atPoint(weights.point[k]);
    return sum;
}

// A side's home (visitCachePoints) is the point of its own layer (IrradianceCache::sidePoints)
// where the side sees it and takes weight from it, which the receivers' search, ranking its
// cell's points by their geometric weight, mostly finds too; skipping that search (it still
// serves the rest) makes the bounces cheaper. The path test stays: without it a turned box's
// lightmap came out worse (docs/speed.md, "Against the speed issue's default").
SideWeights sideWeights(const VoxelScene& voxels, const IrradianceCacheView& cache, const std::vector<uint32_t>& sidePoints) {
    if (sidePoints.size() != voxels.size() * 6)
        throw Error("propagateBounces(" + voxels.sourceScene + "): the gather points were made for " +
                    std::to_string(sidePoints.size() / 6) + " voxels, not " + std::to_string(voxels.size()));
    // Fixed chunks of voxels, each filling its own arrays, joined in chunk order: the same
    // result at any thread count, and no allocation per voxel.
    struct Chunk {
        std::vector<uint32_t> perSlot;  // entries of each side slot of the chunk's voxels
        std::vector<uint32_t> point;
        std::vector<float> weight;
        std::vector<uint32_t> selfGathered;  // global side slots of the chunk with no point
    };
    constexpr size_t kChunkVoxels = 2048;
    const size_t chunks = (voxels.size() + kChunkVoxels - 1) / kChunkVoxels;
    std::vector<Chunk> parts(chunks);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        Chunk& part = parts[c];
        const size_t first = c * kChunkVoxels, last = std::min(voxels.size(), first + kChunkVoxels);
        part.perSlot.assign((last - first) * 6, 0);
        for (size_t i = first; i < last; ++i) {
            const VoxelSides sides = voxelSides(voxels.normal[i], voxels.axisWeights[i].data());
            for (int s = 0; s < sides.count; ++s) {
                const size_t begin = part.point.size();
                const auto take = [&](uint32_t q, float w) {
                    part.point.push_back(q);
                    part.weight.push_back(w);
                };
                const vec3 centre = voxels.centre(i);
                const uint32_t own = sidePoints[i * 6 + size_t(s)];
                const float h = cache.voxelSize;
                const bool ownSeen =
                    own != ~0u && clearPath(cache.occupancy, h, liftOffSurface(centre, sides.normal[s], h),
                                            liftOffSurface(cache.points[own].position, cache.points[own].normal, h),
                                            cache.surfacePlanes);
                float total = ownSeen ? visitFromHome(cache, own, centre, sides.normal[s], take) : 0.0f;
                if (!(total > 0.0f)) {
                    part.point.resize(begin);
                    part.weight.resize(begin);
                    total = visitCachePoints(cache, centre, sides.normal[s], take);
                }
                for (size_t k = begin; k < part.weight.size(); ++k) part.weight[k] /= total;
                part.perSlot[(i - first) * 6 + size_t(s)] = static_cast<uint32_t>(part.point.size() - begin);
                if (part.point.size() == begin) part.selfGathered.push_back(static_cast<uint32_t>(i * 6 + size_t(s)));
            }
        }
    });
    SideWeights out;
    out.begin.assign(voxels.size() * 6 + 1, 0);
    size_t slot = 0;
    for (const Chunk& part : parts) {
        out.point.insert(out.point.end(), part.point.begin(), part.point.end());
        out.weight.insert(out.weight.end(), part.weight.begin(), part.weight.end());
        for (uint32_t count : part.perSlot) {
            out.begin[slot + 1] = out.begin[slot] + count;
            ++slot;
        }
        out.selfGathered.insert(out.selfGathered.end(), part.selfGathered.begin(), part.selfGathered.end());
    }
    return out;
}

// The point where a side no gather point applies to gathers: the voxel's centre, its frame
// from where the voxel lies, not its index, so that it turns with the scene (gatherFrame).
GatherPoint selfPoint(const VoxelScene& voxels, const MipView& view, uint32_t sideSlot) {
    const size_t i = sideSlot / 6;
    const VoxelSides sides = voxelSides(voxels.normal[i], voxels.axisWeights[i].data());
    GatherPoint point;
    point.position = voxels.centre(i);
    point.normal = sides.normal[sideSlot % 6];
    gatherFrame(point.position, point.normal, view.centre(), view.voxelSize, point.tangent, point.turn);
    return point;
}

}  // namespace

std::vector<vec3> applyTransport(const FaceTransport& transport, const std::vector<FaceRadiance>& faces) {
    const size_t slots = faces.size() * 6;
    for (const FaceTransport::Entry& entry : transport.entries)
        if (entry.slot >= slots)
            throw Error("applyTransport: slot " + std::to_string(entry.slot) + " lies past " + std::to_string(slots) +
                        " voxel faces");
    std::vector<vec3> irradiance(transport.pointCount());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, irradiance.size(), 256), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t q = range.begin(); q != range.end(); ++q) {
            vec3 sum(0.0f);
            for (uint32_t k = transport.begin[q]; k < transport.begin[q + 1]; ++k) {
                const FaceTransport::Entry& entry = transport.entries[k];
                sum += entry.weight * faces[entry.slot / 6][entry.slot % 6];
            }
            irradiance[q] = sum;
        }
    });
    return irradiance;
}

Bounced propagateBounces(VoxelScene& voxels, const BounceSettings& bounce, const GatherScene* scene,
                         IrradianceCache givenPoints, Progress* progress) {
    const ConeSettings& settings = bounce.cone;
    const int bounces = bounce.bounces, gatherLevel = bounce.gatherLevel;
    const BounceTail tail = bounce.tail;
    validateConeSettings(settings);
    if (bounces < 0 || bounces > kMaxBounces)
        throw SettingsError("bounces = " + std::to_string(bounces) + " is outside [0, " +
                            std::to_string(kMaxBounces) + "]");
    checkChannels(voxels);
    IrradianceCache::checkLevel(gatherLevel);
    Bounced out;
    if (bounces == 0 || voxels.size() == 0) {
        out.points = std::move(givenPoints);
        return out;
    }
    const bool byRays = bounce.byRays && scene;
    const bool given = givenPoints.level() == gatherLevel && givenPoints.voxelSize() == voxels.voxelSize &&
                       !givenPoints.points().empty();
    IrradianceCache cache = given ? std::move(givenPoints) : IrradianceCache(voxels, gatherLevel);

    const ConeSet& set = coneSet(settings.coneCount);
    std::vector<FaceRadiance> lit = litFaces(voxels);
    std::vector<FaceRadiance> current = lit;
    std::vector<FaceRadiance> next(voxels.size());
    // Rays read level 0 alone; cones want the coarser levels too.
    RadianceMips mips = byRays ? buildLevelZeroMips(voxels, isotropic(voxels, current), current)
                                         : buildRadianceMips(voxels, isotropic(voxels, current), current);
    cache.link(mips.view());
    const SideWeights weights = sideWeights(voxels, cache.view(mips.view()), cache.sidePoints());
    std::vector<vec3> selfIrradiance(weights.selfGathered.size());
    // By transport, the cache's points and then the self-gathered sides' are one map.
    const bool skyLit = bounce.skyLit && scene &&
                        (maxComponent(scene->scene.sky.uniform) > 0.0f || scene->scene.sky.hasImage());
    const FaceTransport* transport = nullptr;
    std::vector<GatherPoint> points;
    if (byRays || skyLit) {
        points = cache.points();
        for (uint32_t sideSlot : weights.selfGathered) points.push_back(selfPoint(voxels, mips.view(), sideSlot));
    }
    const float h = static_cast<float>(voxels.voxelSize);
    if (byRays) {
        out.transport = rayTransport(points, mips.view(), voxels.size(), scene->bvh, scene->scene, bounce.raysPerAxis,
                                     bounce.skyDrawsPerAxis);
        transport = &out.transport;
    }
    // Each voxel's faces' sides (voxelSides), once for the sky and every bounce below.
    std::vector<FaceSides> faceSides(voxels.size());
    tbb::parallel_for(size_t(0), voxels.size(), [&](size_t i) {
        const VoxelSides sides = voxelSides(voxels.normal[i], voxels.axisWeights[i].data());
        faceSides[i].count = static_cast<int8_t>(sides.count);
        for (size_t f = 0; f < 6; ++f) faceSides[i].side[f] = static_cast<int8_t>(sides.sideOfFace[f]);
    });
    if (skyLit) {
        // The sky's light at every point: an image sky's by the receivers' estimate (or, where
        // the transport's rays hold their part, those plus the image's draws), a uniform sky's
        // by how open each point is.
        std::vector<vec3> skyE;
        const BvhView& bvh = scene->bvh;
        const TraceSceneView& view = scene->scene;
        if (view.sky.hasImage() && transport && transport->skyCosine.size() == points.size()) {
            skyE = skyImageDrawsAtPoints(points, h, bvh, view, bounce.skyDrawsPerAxis, bounce.raysPerAxis);
            for (size_t q = 0; q < skyE.size() && q < points.size(); ++q) skyE[q] += transport->skyCosine[q];
        } else if (view.sky.hasImage()) {
            skyE = skyIrradianceAtPoints(points, h, bvh, view, bounce.skyDrawsPerAxis);
        } else {
            const std::vector<float> open = transport && transport->open.size() == points.size()
                                                ? transport->open
                                                : skyOpenness(points, h, bvh, view, bounce.raysPerAxis);
            skyE.resize(open.size());
            for (size_t q = 0; q < open.size(); ++q) skyE[q] = view.sky.uniform * open[q];
        }
        if (skyE.size() != points.size())
            throw Error("propagateBounces(" + voxels.sourceScene + "): the sky's light has " +
                        std::to_string(skyE.size()) + " points, not " + std::to_string(points.size()));
        const size_t cachePoints = cache.points().size();
        tbb::parallel_for(size_t(0), voxels.size(), [&](size_t i) {
            const vec3 reflectance = voxels.albedo[i] * kInvPi;
            for (size_t f = 0; f < 6; ++f) {
                const int s = faceSides[i].side[f];
                if (s < 0) continue;
                lit[i][f] += reflectance * sideValue<vec3>(
                                               weights, i * 6 + size_t(s), [&](uint32_t q) { return skyE[q]; },
                                               [&](size_t k) { return skyE[cachePoints + k]; });
            }
        });
        current = lit;
        // Cones read the mips, built above from the light without the sky.
        if (!transport) mips.relight(voxels, isotropic(voxels, current), current);
    }
    const size_t addedChunks = (voxels.size() + kAddedChunkVoxels - 1) / kAddedChunkVoxels;
    double added = 0.0, addedBefore = 0.0;  // light the last two bounces added
    std::vector<FaceRadiance> older;  // L two bounces before the last, for the tail's local ratios
    for (int b = 0; b < bounces; ++b) {
        if (tail == BounceTail::Geometric && b == bounces - 1 && b >= 1) older = next;
        if (transport) {
            std::vector<vec3> irradiance = applyTransport(*transport, current);
            std::copy(irradiance.begin() + std::ptrdiff_t(cache.points().size()), irradiance.end(), selfIrradiance.begin());
            irradiance.resize(cache.points().size());
            cache.setIrradiance(std::move(irradiance));
        } else {
            if (b > 0) mips.relight(voxels, isotropic(voxels, current), current);
            const MipView view = mips.view();
            cache.gather(view, settings);
            tbb::parallel_for(size_t(0), weights.selfGathered.size(), [&](size_t k) {
                const GatherPoint point = selfPoint(voxels, view, weights.selfGathered[k]);
                selfIrradiance[k] = coneTraceIrradiance(view, point.position, point.normal, set, settings, nullptr,
                                                        point.turn, &point.tangent);
            });
        }
        const MipView view = mips.view();
        const IrradianceCacheView points = cache.view(view);
        // The light this bounce adds is summed in the same pass (kAddedChunkVoxels).
        std::vector<double> partial(addedChunks, 0.0);
        tbb::parallel_for(size_t(0), addedChunks, [&](size_t c) {
            double sum = 0.0;
            const size_t last = std::min(voxels.size(), (c + 1) * kAddedChunkVoxels);
            for (size_t i = c * kAddedChunkVoxels; i < last; ++i) {
                const FaceSides& sides = faceSides[i];
                vec3 e[6];
                for (int s = 0; s < sides.count; ++s)
                    e[s] = sideValue<vec3>(
                        weights, i * 6 + size_t(s), [&](uint32_t q) { return points.irradiance[q]; },
                        [&](size_t k) { return selfIrradiance[k]; });
                const vec3 reflectance = voxels.albedo[i] * kInvPi;
                for (size_t f = 0; f < 6; ++f) {
                    next[i][f] = lit[i][f] + (sides.side[f] >= 0 ? reflectance * e[sides.side[f]] : vec3(0.0f));
                    const vec3 d = next[i][f] - current[i][f];
                    sum += double(voxels.axisWeights[i][f]) * double(d.x + d.y + d.z);
                }
            }
            partial[c] = sum;
        });
        if (progress) progress->advance(voxels.size());
        current.swap(next);
        addedBefore = added;
        added = 0.0;
        for (double p : partial) added += p;
    }
    // The series' tail: each further bounce adds r times what the last one did, so the rest
    // sums to ΔL·r/(1 − r) (Cohen et al. 1988's ambient term, from the iteration itself). r is
    // each face's own ratio of its last two increments, capped by the ratio of the whole
    // scene's: after a few bounces the parts of a scene have not yet settled to one rate, and the
    // scene's ratio belongs to whatever keeps its light longest, while the rooms a camera sees
    // may lose theirs faster. The cap keeps a face whose increments are still growing (light
    // arriving late) from blowing up. Why a tail at all: a bright interior keeps most of its
    // light for many bounces; the tail takes it to the limit for the price of none
    // (docs/decisions.md, "Bounces").
    if (tail == BounceTail::Geometric && bounces >= 2 && addedBefore > 0.0 && added > 0.0) {
        const float r = static_cast<float>(std::min(added / addedBefore, kMaxTailRatio));
        tbb::parallel_for(size_t(0), voxels.size(), [&](size_t i) {
            for (size_t f = 0; f < 6; ++f) {
                const vec3 last = current[i][f] - next[i][f], before = next[i][f] - older[i][f];
                const float lastSum = last.x + last.y + last.z, beforeSum = before.x + before.y + before.z;
                const float local = beforeSum > 0.0f ? glm::clamp(lastSum / beforeSum, 0.0f, r) : r;
                current[i][f] += local / (1.0f - local) * last;
            }
        });
    }
    voxels.radiance = isotropic(voxels, current);
    voxels.faceRadiance = std::move(current);
    mips.relight(voxels, voxels.radiance, voxels.faceRadiance);
    out.mips = std::move(mips);
    out.points = std::move(cache);
    return out;
}

}  // namespace vl
