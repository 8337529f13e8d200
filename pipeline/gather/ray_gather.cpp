#include "gather/ray_gather.h"

#include "lighting/direct_light.h"
#include "gather/fan_rays.h"
#include "gather/shade_element.h"

#include "cone/cone_trace.h"
#include "core/error.h"
#include "core/progress.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "trace/bvh_traverse.h"
#include "trace/path_kernels.h"
#include "trace/ray_offset.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>

namespace vl {

namespace {

void checkRays(int raysPerAxis) {
    if (raysPerAxis < 1 || raysPerAxis > kMaxGatherRaysPerAxis)
        throw SettingsError("gather rays " + std::to_string(raysPerAxis) + " per axis is outside 1.." +
                            std::to_string(kMaxGatherRaysPerAxis));
}

using RayFan = FanStart;

RayFan rayFan(const GatherPoint& point, float h, const BvhView& bvh, const TraceSceneView& scene) {
    RayFan fan;
    fan.frame = fanFrame(point.normal, point.tangent, point.turn);
    const vec3 across = glm::cross(point.normal, point.tangent);
    // The point's surface under it; where none lies within three voxels under it (the point's
    // voxels straddle the surface's edge), under a point a voxel to one side. The side tries
    // matter only on turned scenes, and little there.
    const vec3 lifted = liftOffSurface(point.position, point.normal, h);
    fan.origin = lifted;
    const vec3 shifts[] = {vec3(0.0f), point.tangent, -point.tangent, across, -across};
    for (const vec3& shift : shifts) {
        Ray back;
        back.origin = lifted + shift * h;
        back.direction = -point.normal;
        back.tMax = 3.0f * h;
        Hit hit;
        if (!intersectClosest(bvh, back, hit)) continue;
        const vec3 n = surfaceAt(scene, hit.triangle, hit.b1, hit.b2).geometricNormal;
        // Only the point's own surface, which faces its way: at a wall's top edge the ray
        // back under a point leaning a few degrees up passed over the edge onto the roof, and
        // half the fan's rays, leaving that roof downward, read its sunlit top as light arriving
        // at the wall (docs/decisions.md, "Sky sampling": a gather fan on the wrong surface).
        if (glm::abs(glm::dot(n, point.normal)) < 0.5f) continue;
        fan.origin = offsetRayOrigin(back.at(hit.t), glm::dot(n, point.normal) >= 0.0f ? n : -n, bvh.extent);
        break;
    }
    return fan;
}

// The n × n cosine-distributed, stratified directions about +Z that every fan lays out in its
// own frame (the same for every point: computed once per gather).
std::vector<vec3> fanPattern(int n) {
    std::vector<vec3> pattern;
    pattern.reserve(size_t(n) * size_t(n));
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) pattern.push_back(fanDirection(i, j, n));
    return pattern;
}

// Traces the fan's rays in `pattern` and calls onHit(ray, closest hit) for each that hits,
// onEscape(ray) for each that leaves the scene.
template <typename OnEscape, typename OnHit>
void traceFan(const RayFan& fan, const std::vector<vec3>& pattern, const BvhView& bvh, OnEscape&& onEscape, OnHit&& onHit) {
    const bool jittered = fan.jitter.x >= 0.0f;
    const int n = jittered ? int(std::lround(std::sqrt(double(pattern.size())))) : 0;
    for (size_t k = 0; k < pattern.size(); ++k) {
        Ray ray;
        ray.origin = fan.origin;
        ray.direction = inFrame(fan.frame, jittered ? fanDirectionJittered(int(k) / n, int(k) % n, n, fan.jitter) : pattern[k]);
        Hit hit;
        if (intersectClosest(bvh, ray, hit))
            onHit(ray, hit);
        else
            onEscape(ray);
    }
}

template <typename OnHit>
void traceFan(const RayFan& fan, const std::vector<vec3>& pattern, const BvhView& bvh, OnHit&& onHit) {
    traceFan(fan, pattern, bvh, [](const Ray&) {}, onHit);
}

// Level 0's index and, per voxel, the coverage of its six texels side by side: what a ray
// reads where it hits. Read in place (24-byte texels, six per voxel) the coverages cost the
// gather most of its time in cache misses; a voxel's six coverages share one cache line. They
// are kept in 1/255ths: the reads only rank a voxel against its two neighbours and test for a
// whole face, and six bytes a voxel keep a small scene's level 0 inside one core's L2.
//
// A ray's hit lands anywhere, so the leaf it reads is seldom the last one read: walking the
// tree from its root to each leaf (the upper node's 32³ child table alone is 256 kB) missed
// the cache at every level. Where the grid's box of 8³ leaves holds at most kMaxLeafSlots,
// the leaves are found in one flat table of that box instead. The profile behind both:
// docs/speed.md, "The ray gather's memory reads".
struct HitLookup {
    using Leaf = IndexLeafCache::Leaf;
    using Coverage = uint8_t;
    static constexpr uint8_t kWhole = 255;
    static constexpr size_t kMaxLeafSlots = size_t(1) << 21;  // 16 MB of pointers
    const MipIndexGrid* index = nullptr;
    float inverseVoxelSize = 0.0f;
    std::vector<std::array<uint8_t, 6>> coverages;  // per voxel, by direction of travel
    ivec3 leafMin = ivec3(0), leafSlots = ivec3(0);  // the table's box, in leaves
    std::vector<const Leaf*> leaves;                 // empty: the tree is walked

    // The voxel index at c, or -1 where no voxel is.
    int32_t voxelAt(IndexLeafCache& cache, const ivec3& c) const {
        const nanovdb::Coord ijk(c.x, c.y, c.z);
        if (leaves.empty()) return cache.value(*index, ijk);
        const ivec3 slot = ivec3(c.x >> 3, c.y >> 3, c.z >> 3) - leafMin;
        if (slot.x < 0 || slot.y < 0 || slot.z < 0 || slot.x >= leafSlots.x || slot.y >= leafSlots.y ||
            slot.z >= leafSlots.z)
            return -1;
        const Leaf* leaf = leaves[(size_t(slot.z) * size_t(leafSlots.y) + size_t(slot.y)) * size_t(leafSlots.x) +
                                  size_t(slot.x)];
        return leaf ? leaf->getValue(Leaf::CoordToOffset(ijk)) : -1;
    }
    uint8_t coverage(int32_t voxel, int travel) const { return coverages[size_t(voxel)][size_t(travel)]; }
};

void tableLeaves(HitLookup& lookup) {
    const auto& tree = lookup.index->tree();
    const uint32_t count = tree.nodeCount(0);
    const HitLookup::Leaf* first = tree.getFirstLeaf();
    if (count == 0 || !first) return;
    ivec3 lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
    for (uint32_t k = 0; k < count; ++k) {
        const nanovdb::Coord o = first[k].origin();
        const ivec3 leaf(o[0] >> 3, o[1] >> 3, o[2] >> 3);
        lo = glm::min(lo, leaf);
        hi = glm::max(hi, leaf);
    }
    const ivec3 slots = hi - lo + ivec3(1);
    if (double(slots.x) * double(slots.y) * double(slots.z) > double(HitLookup::kMaxLeafSlots)) return;
    lookup.leafMin = lo;
    lookup.leafSlots = slots;
    lookup.leaves.assign(size_t(slots.x) * size_t(slots.y) * size_t(slots.z), nullptr);
    for (uint32_t k = 0; k < count; ++k) {
        const nanovdb::Coord o = first[k].origin();
        const ivec3 slot = ivec3(o[0] >> 3, o[1] >> 3, o[2] >> 3) - lo;
        lookup.leaves[(size_t(slot.z) * size_t(slots.y) + size_t(slot.y)) * size_t(slots.x) + size_t(slot.x)] = &first[k];
    }
}

HitLookup hitLookup(const MipLevelView& level0, size_t voxels) {
    HitLookup lookup;
    lookup.index = level0.index;
    lookup.inverseVoxelSize = level0.inverseVoxelSize;
    tableLeaves(lookup);
    lookup.coverages.resize(voxels);
    tbb::parallel_for(size_t(0), voxels, [&](size_t i) {
        for (size_t t = 0; t < 6; ++t) {
            const float c = glm::clamp(level0.texels[i * size_t(level0.facesPerVoxel) + t].coverage, 0.0f, 1.0f);
            // A sliver of surface still shows: it rounds up to 1, never to nothing.
            lookup.coverages[i][t] = c > 0.0f ? static_cast<uint8_t>(std::max(1l, std::lround(c * float(HitLookup::kWhole)))) : 0;
        }
    });
    return lookup;
}

// The lights' (punctual) direct light the hit point reflects back along the ray: shadowed,
// × its albedo / π, on the side the ray meets; a sun's disk at one point drawn from `draws`.
vec3 lightsReflectedAt(const TraceSceneView& scene, const BvhView& bvh, const Ray& ray, const Hit& hit, Pcg32& draws) {
    const SurfaceHit h = surfaceAt(scene, hit.triangle, hit.b1, hit.b2);
    const vec3 side = glm::dot(h.geometricNormal, ray.direction) < 0.0f ? h.geometricNormal : -h.geometricNormal;
    vec2 u;
    draws.next2D(u.x, u.y);
    const uint64_t seed = scene.pointLightTree.nodes ? draws.nextU32() : 0;
    return baseColorAt(scene, h) * kInvPi * punctualLightsIrradiance(scene, bvh, h.position, side, side, u, kHitLightCut, seed);
}

}  // namespace

std::vector<vec2> fanTurnWeights(int n) {
    constexpr int kPoints = 16;  // per axis of a stratum
    std::vector<vec2> weights(size_t(n) * size_t(n), vec2(0.0f));
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int a = 0; a < kPoints; ++a)
                for (int b = 0; b < kPoints; ++b) {
                    const vec2 d = sampleConcentricDisk(
                        vec2(float(i) + (float(a) + 0.5f) / kPoints, float(j) + (float(b) + 0.5f) / kPoints) / float(n));
                    weights[size_t(i * n + j)] +=
                        d / (std::sqrt(std::max(1e-6f, 1.0f - glm::dot(d, d))) * float(kPoints * kPoints));
                }
    return weights;
}

std::vector<vec3> gatherFans(const std::vector<FanStart>& fans, const MipView& mips,
                             const std::vector<FaceRadiance>& faces, const BvhView& bvh, const TraceSceneView& scene,
                             int raysPerAxis, Progress* progress, FanExtras* extras, int skyDrawsPerAxis) {
    checkRays(raysPerAxis);
    std::vector<vec3> irradiance(fans.size(), vec3(0.0f));
    if (extras) {
        extras->sky.assign(fans.size(), vec3(0.0f));
        extras->variance.assign(fans.size(), 0.0f);
        extras->escaped.assign(fans.size(), 0u);
        extras->rotation.assign(extras->rotationGradients ? fans.size() : 0, RotationGradients{});
    }
    if (mips.levelCount <= 0) return irradiance;
    const std::vector<vec3> pattern = fanPattern(raysPerAxis);
    const float rays = float(pattern.size());
    const bool rotation = extras && extras->rotationGradients;
    const std::vector<vec2> turnWeights = rotation ? fanTurnWeights(raysPerAxis) : std::vector<vec2>();
    const HitLookup level0 = hitLookup(mips.levels[0], faces.size());
    const bool sky = extras && extras->readSky && scene.sky.present();
    const std::vector<FaceRadiance>* lights = extras && scene.lightCount > 0 ? extras->lightsAtHits : nullptr;
    const float imageDraws = scene.sky.samplable() ? float(skyDrawsPerAxis * skyDrawsPerAxis) : 0.0f;
    // The light a hit sends back along the ray, read from its voxels (less the lights' part,
    // taken at the hit itself by a shadow ray, with lightsAtHits).
    const auto readVoxels = [&](const Ray& ray, const Hit& hit, Pcg32& lightDraws, IndexLeafCache& leaves) {
        vec3 L(0.0f);
        readHitTexels(level0, leaves, ray.at(hit.t), ray.direction, windingCross(scene, hit.triangle),
                      [&](int32_t voxel, int travel, float weight) {
                          L += weight * faces[size_t(voxel)][size_t(travel ^ 1)];
                          if (lights) L -= weight * (*lights)[size_t(voxel)][size_t(travel ^ 1)];
                      });
        if (lights) L = glm::max(L, vec3(0.0f)) + lightsReflectedAt(scene, bvh, ray, hit, lightDraws);
        return L;
    };
    // The same light for a near hit (FanExtras::nearField): a path of cosine rays from it, each
    // of its vertices nearer than nearField to the last reflecting its lights and what the next
    // ray brings back, the first farther one (or the kNearFieldBounces-th) read from its voxels.
    // Both sides of a surface reflect, as in the path tracer.
    // Only where every hit's lights can be taken by a shadow ray: without lightsAtHits a
    // scene's lights live in the faces a traced hit no longer reads.
    const float nearField = extras && (scene.lightCount == 0 || lights) ? extras->nearField : 0.0f;
    const auto tracedOn = [&](const Ray& first, const Hit& firstHit, Pcg32& lightDraws, Pcg32& nearDraws,
                              IndexLeafCache& leaves, uint64_t& traced) {
        vec3 L(0.0f), throughput(1.0f);
        Ray ray = first;
        Hit hit = firstHit;
        for (int depth = 0;; ++depth) {
            const SurfaceHit h = surfaceAt(scene, hit.triangle, hit.b1, hit.b2);
            // Seen from a bounce, an emitter's light is indirect; the first hit's is the
            // receiver's own direct light.
            if (depth > 0) L += throughput * emissionAt(scene, h, -ray.direction);
            if (depth == kNearFieldBounces || (depth > 0 && hit.t >= nearField)) {
                L += throughput * readVoxels(ray, hit, lightDraws, leaves);
                break;
            }
            if (lights) L += throughput * lightsReflectedAt(scene, bvh, ray, hit, lightDraws);
            throughput *= baseColorAt(scene, h);
            if (!(std::max(throughput.x, std::max(throughput.y, throughput.z)) > 1e-3f)) break;
            const vec3 side = glm::dot(h.geometricNormal, ray.direction) < 0.0f ? h.geometricNormal : -h.geometricNormal;
            vec2 u;
            nearDraws.next2D(u.x, u.y);
            Ray next;
            next.origin = offsetRayOrigin(h.position, side, bvh.extent);
            next.direction = sampleDiffuseDirection(side, u);
            ++traced;
            Hit nextHit;
            if (!intersectClosest(bvh, next, nextHit)) {
                if (scene.sky.present()) L += throughput * skySeenAlong(scene.sky, next.direction).radiance;
                break;
            }
            ray = next;
            hit = nextHit;
        }
        return L;
    };
    std::atomic<uint64_t> nearHitCount{0}, nearRayCount{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, fans.size(), 16), [&](const tbb::blocked_range<size_t>& range) {
        IndexLeafCache leaves;
        uint64_t nearHits = 0, nearRays = 0;
        for (size_t q = range.begin(); q != range.end(); ++q) {
            Pcg32 lightDraws = Pcg32::forItem(fans[q].seed, 0, 0x48495453ull);  // "HITS": the suns' disk points
            Pcg32 nearDraws = Pcg32::forItem(fans[q].seed, 0, 0x4e454152ull);   // "NEAR": the near field's paths
            vec3 sum(0.0f), open(0.0f);
            double squares = 0.0, values = 0.0;  // of every ray's radiance, the sky's too
            uint32_t escaped = 0;
            RotationGradients turned;
            size_t slot = 0;  // the ray's stratum in the fan
            // A ray's light and sky into the rotation gradients, by its stratum's weight.
            const auto turn = [&](const vec3& light, const vec3& skyLight) {
                const vec2 w = turnWeights[slot];
                const vec3 along = (kPi / rays) * (w.x * fans[q].frame.tangent + w.y * fans[q].frame.bitangent);
                turned.light += glm::outerProduct(light, along);
                turned.sky += glm::outerProduct(skyLight, along);
            };
            traceFan(
                fans[q], pattern, bvh,
                [&](const Ray& ray) {
                    ++escaped;
                    if (!sky) {
                        ++slot;
                        return;
                    }
                    vec3 L;
                    if (scene.sky.hasImage()) {
                        const SkySeen seen = skySeenAlong(scene.sky, ray.direction);
                        open += skyShare(seen, glm::dot(fans[q].frame.normal, ray.direction), rays, imageDraws);
                        L = seen.radiance;
                    } else {
                        open += scene.sky.uniform * (kPi / rays);
                        L = scene.sky.uniform;
                    }
                    if (rotation) turn(vec3(0.0f), L);
                    ++slot;
                    const double l = (double(L.x) + double(L.y) + double(L.z)) / 3.0;
                    squares += l * l;
                    values += l;
                },
                [&](const Ray& ray, const Hit& hit) {
                    const vec3 L = hit.t < nearField ? tracedOn(ray, hit, lightDraws, nearDraws, leaves, nearRays)
                                                     : readVoxels(ray, hit, lightDraws, leaves);
                    if (hit.t < nearField) ++nearHits;
                    if (rotation) turn(L, vec3(0.0f));
                    ++slot;
                    sum += L;
                    const double l = (double(L.x) + double(L.y) + double(L.z)) / 3.0;
                    squares += l * l;
                    values += l;
                });
            irradiance[q] = sum * (kPi / rays);
            if (extras) {
                // E = π/n Σ L_i (the sky's rays too): its variance is π²/n times the rays'.
                const double mean = values / double(rays);
                const double spread = std::max(0.0, squares / double(rays) - mean * mean);
                extras->variance[q] = float(double(kPi) * double(kPi) * spread / double(rays));
                extras->escaped[q] = escaped;
                if (sky && scene.sky.samplable() && skyDrawsPerAxis > 0)
                    open += skyImageDrawsIrradiance(scene, bvh, fans[q].origin, fans[q].frame.normal, fans[q].frame.normal,
                                                    skyDrawsPerAxis, rays, fans[q].seed);
                extras->sky[q] = isFinite(open) ? open : vec3(0.0f);
                if (rotation) extras->rotation[q] = turned;
            }
        }
        nearHitCount += nearHits;
        nearRayCount += nearRays;
        if (progress) progress->advance(range.size());
    });
    if (extras) {
        extras->nearHits = nearHitCount;
        extras->nearRays = nearRayCount;
    }
    return irradiance;
}

std::vector<vec3> gatherByRays(const std::vector<GatherPoint>& points, const MipView& mips,
                               const std::vector<FaceRadiance>& faces, const BvhView& bvh, const TraceSceneView& scene,
                               int raysPerAxis, Progress* progress) {
    std::vector<FanStart> fans(points.size());
    const float h = mips.voxelSize;
    tbb::parallel_for(size_t(0), points.size(), [&](size_t q) {
        fans[q] = rayFan(points[q], h, bvh, scene);
        fans[q].seed = q;
    });
    return gatherFans(fans, mips, faces, bvh, scene, raysPerAxis, progress);
}

FaceTransport rayTransport(const std::vector<GatherPoint>& points, const MipView& mips, size_t voxelCount,
                           const BvhView& bvh, const TraceSceneView& scene, int raysPerAxis, int skyDrawsPerAxis,
                           Progress* progress) {
    checkRays(raysPerAxis);
    FaceTransport transport;
    transport.begin.assign(points.size() + 1, 0);
    if (mips.levelCount <= 0) return transport;
    const float h = mips.voxelSize;
    const std::vector<vec3> pattern = fanPattern(raysPerAxis);
    const float rayWeight = kPi / float(pattern.size());
    const HitLookup level0 = hitLookup(mips.levels[0], voxelCount);
    // Fixed chunks of points, each filling its own arrays, joined in chunk order: the same
    // transport at any thread count.
    struct Chunk {
        std::vector<uint32_t> count;  // entries per point of the chunk
        std::vector<FaceTransport::Entry> entries;
        std::vector<float> open;      // per point of the chunk
        std::vector<vec3> skyCosine;  // per point of the chunk, under an image sky
    };
    const bool imageSky = scene.sky.hasImage() && skyDrawsPerAxis > 0;
    const float cosineRays = float(pattern.size());
    const float imageDraws = scene.sky.samplable() ? float(skyDrawsPerAxis * skyDrawsPerAxis) : 0.0f;
    // Many rays of a point read the same face: each thread sums a point's weights per face in
    // a dense scratch array (summed in ray order, whichever thread it is), then lists the
    // faces read in order and clears them.
    struct Scratch {
        std::vector<float> weight;  // per slot, 0 where the current point read nothing
        std::vector<uint32_t> read;
    };
    tbb::enumerable_thread_specific<Scratch> scratches;
    constexpr size_t kChunkPoints = 64;
    const size_t chunks = (points.size() + kChunkPoints - 1) / kChunkPoints;
    std::vector<Chunk> parts(chunks);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        Chunk& part = parts[c];
        Scratch& scratch = scratches.local();
        scratch.weight.resize(voxelCount * 6, 0.0f);  // once per thread: every slot a hit can read
        IndexLeafCache leaves;
        const size_t first = c * kChunkPoints, last = std::min(points.size(), first + kChunkPoints);
        for (size_t q = first; q < last; ++q) {
            size_t hits = 0;
            const RayFan fan = rayFan(points[q], h, bvh, scene);
            vec3 sky(0.0f);
            const auto escaped = [&](const Ray& ray) {
                if (imageSky)
                    sky += skyShare(skySeenAlong(scene.sky, ray.direction), glm::dot(fan.frame.normal, ray.direction), cosineRays,
                                    imageDraws);
            };
            traceFan(fan, pattern, bvh, escaped, [&](const Ray& ray, const Hit& hit) {
                ++hits;
                readHitTexels(level0, leaves, ray.at(hit.t), ray.direction, windingCross(scene, hit.triangle),
                              [&](int32_t voxel, int travel, float weight) {
                                  // The texel of travel t shows face t ^ 1 (radiance_mips.h).
                                  const uint32_t slot = uint32_t(voxel) * 6u + uint32_t(travel ^ 1);
                                  if (scratch.weight[slot] == 0.0f) scratch.read.push_back(slot);
                                  scratch.weight[slot] += weight * rayWeight;
                              });
            });
            std::sort(scratch.read.begin(), scratch.read.end());
            for (uint32_t slot : scratch.read) {
                part.entries.push_back({slot, scratch.weight[slot]});
                scratch.weight[slot] = 0.0f;
            }
            part.count.push_back(static_cast<uint32_t>(scratch.read.size()));
            part.open.push_back(rayWeight * static_cast<float>(pattern.size() - hits));
            if (imageSky) part.skyCosine.push_back(sky);
            scratch.read.clear();
        }
        if (progress) progress->advance(last - first);
    });
    size_t q = 0;
    transport.open.reserve(points.size());
    for (const Chunk& part : parts) {
        transport.entries.insert(transport.entries.end(), part.entries.begin(), part.entries.end());
        transport.open.insert(transport.open.end(), part.open.begin(), part.open.end());
        transport.skyCosine.insert(transport.skyCosine.end(), part.skyCosine.begin(), part.skyCosine.end());
        for (uint32_t count : part.count) {
            transport.begin[q + 1] = transport.begin[q] + count;
            ++q;
        }
    }
    return transport;
}

namespace {

// Per point, `atFan(q, its fan)` (TBB-parallel, each point on its own: the same at any
// thread count).
template <typename T, typename AtFan>
std::vector<T> perFan(const std::vector<GatherPoint>& points, float voxelSize, const BvhView& bvh,
                      const TraceSceneView& scene, AtFan&& atFan) {
    std::vector<T> values(points.size());
    tbb::parallel_for(size_t(0), points.size(),
                      [&](size_t q) { values[q] = atFan(q, rayFan(points[q], voxelSize, bvh, scene)); });
    return values;
}

}  // namespace

std::vector<vec3> fanOrigins(const std::vector<GatherPoint>& points, float voxelSize, const BvhView& bvh,
                             const TraceSceneView& scene) {
    return perFan<vec3>(points, voxelSize, bvh, scene, [](size_t, const RayFan& fan) { return fan.origin; });
}

std::vector<float> skyOpenness(const std::vector<GatherPoint>& points, float voxelSize, const BvhView& bvh,
                               const TraceSceneView& scene, int raysPerAxis) {
    checkRays(raysPerAxis);
    const std::vector<vec3> pattern = fanPattern(raysPerAxis);
    const float rayWeight = kPi / float(pattern.size());
    return perFan<float>(points, voxelSize, bvh, scene, [&](size_t, const RayFan& fan) {
        size_t hits = 0;
        traceFan(fan, pattern, bvh, [&](const Ray&, const Hit&) { ++hits; });
        return rayWeight * static_cast<float>(pattern.size() - hits);
    });
}

std::vector<vec3> skyIrradianceAtPoints(const std::vector<GatherPoint>& points, float voxelSize, const BvhView& bvh,
                                        const TraceSceneView& scene, int strata) {
    return perFan<vec3>(points, voxelSize, bvh, scene, [&](size_t q, const RayFan& fan) {
        return skyIrradiance(scene, bvh, fan.origin, fan.frame.normal, fan.frame.normal, strata, uint64_t(q));
    });
}

std::vector<vec3> skyImageDrawsAtPoints(const std::vector<GatherPoint>& points, float voxelSize, const BvhView& bvh,
                                        const TraceSceneView& scene, int drawsPerAxis, int raysPerAxis) {
    const float cosineRays = float(raysPerAxis * raysPerAxis);
    return perFan<vec3>(points, voxelSize, bvh, scene, [&](size_t q, const RayFan& fan) {
        return skyImageDrawsIrradiance(scene, bvh, fan.origin, fan.frame.normal, fan.frame.normal, drawsPerAxis, cosineRays,
                                       uint64_t(q));
    });
}

BackProbe probeSingleSidedBacks(const std::vector<GatherPoint>& points, float voxelSize, const BvhView& bvh,
                                const TraceSceneView& scene, int raysPerAxis) {
    checkRays(raysPerAxis);
    const std::vector<vec3> pattern = fanPattern(raysPerAxis);
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, points.size(), 64), BackProbe(),
        [&](const tbb::blocked_range<size_t>& range, BackProbe probe) {
            for (size_t q = range.begin(); q != range.end(); ++q) {
                traceFan(rayFan(points[q], voxelSize, bvh, scene), pattern, bvh, [&](const Ray& ray, const Hit& hit) {
                    ++probe.hits;
                    if (glm::dot(ray.direction, windingCross(scene, hit.triangle)) > 0.0f &&
                        !scene.materials[scene.materialIds[hit.triangle]].doubleSided)
                        ++probe.singleSidedBacks;
                });
            }
            return probe;
        },
        [](BackProbe a, const BackProbe& b) {
            a.hits += b.hits;
            a.singleSidedBacks += b.singleSidedBacks;
            return a;
        });
}

GatherVisibility parseGatherVisibility(const std::string& text) {
    if (text == "auto") return GatherVisibility::Auto;
    if (text == "cones") return GatherVisibility::Cones;
    if (text == "rays") return GatherVisibility::Rays;
    throw SettingsError("setting gather-visibility = '" + text + "' is not one of auto, cones, rays");
}

const char* toString(GatherVisibility visibility) {
    switch (visibility) {
        case GatherVisibility::Cones: return "cones";
        case GatherVisibility::Rays: return "rays";
        case GatherVisibility::Auto: break;
    }
    return "auto";
}

GatherVisibilityChoice chooseGatherVisibility(GatherVisibility requested, const IrradianceCache& points,
                                              const BvhView& bvh, const TraceSceneView& scene) {
    GatherVisibilityChoice choice;
    if (requested != GatherVisibility::Auto) {
        choice.visibility = requested;
        choice.setBy = "the gather-visibility setting";
        return choice;
    }
    choice.probe = probeSingleSidedBacks(points.points(), float(points.voxelSize()), bvh, scene, kProbeRaysPerAxis);
    const double share = choice.probe.share();
    choice.visibility = share > kBackShareLimit ? GatherVisibility::Cones : GatherVisibility::Rays;
    char text[200];
    std::snprintf(text, sizeof text, "%.1f%% of %llu probe rays hit the back of a single-sided surface (rays up to %.0f%%)",
                  100.0 * share, static_cast<unsigned long long>(choice.probe.hits), 100.0 * kBackShareLimit);
    choice.setBy = text;
    return choice;
}

std::string describeGatherVisibility(const GatherVisibilityChoice& choice) {
    return std::string("gather visibility: ") + toString(choice.visibility) + " (" + choice.setBy + ")";
}

}  // namespace vl
