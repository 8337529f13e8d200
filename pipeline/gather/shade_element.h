// One bake receiver element (a lightmap texel or a pixel): the exact direct term and the
// cone-traced indirect term as E/π, plain and times the samples' albedo. Written once for
// shadeReceivers (TBB) and the CUDA launcher.
#pragma once

#include "lighting/direct_light.h"
#include "gather/fan_rays.h"
#include "cone/cone_set.h"
#include "cone/cone_trace.h"
#include "gather/irradiance_cache.h"
#include "core/sampling.h"
#include "trace/bvh_traverse.h"
#include "trace/ray_offset.h"
#include "trace/trace_scene.h"
#include "trace/surface_samples.h"

#include <cstdint>

namespace vl {

// A receiver inside closed geometry (a floor texel under a block standing on it) gets no
// light, but the voxels cannot tell: its cones start above the surface, inside the block,
// and gather light through the block's one-voxel walls at coarse levels. The exact
// geometry can: probe rays from such a point meet the inside (the back) of the enclosing
// surfaces. A sample is buried when more than half of kBuriedProbeRays cosine-distributed
// rays first hit a surface from behind its shading normal; it then gets no indirect light
// (its direct term, from shadow rays, is already zero). The majority rule keeps an open
// receiver open where a few surfaces face away from it (an exporter's flipped wall). A
// sample that a light reaches is open to it and is not probed: where most texels see the light
// the probe rays were a large share of the lightmap's shading, and the lightmap comes out the
// same without them (docs/speed.md, "Against the speed issue's default").
constexpr int kBuriedProbesPerAxis = 4;
constexpr int kBuriedProbeRays = kBuriedProbesPerAxis * kBuriedProbesPerAxis;

VL_HOSTDEV inline bool isBuried(const TraceSceneView& scene, const BvhView& bvh, const SurfaceSample& r) {
    vec3 tangent, bitangent;
    orthonormalBasis(r.normal, tangent, bitangent);
    Ray ray;
    ray.origin = offsetRayOrigin(r.position, r.normal, bvh.extent);
    int fromBehind = 0;
    for (int a = 0; a < kBuriedProbesPerAxis; ++a)
        for (int b = 0; b < kBuriedProbesPerAxis; ++b) {
            const vec3 d = sampleCosineHemisphere(
                vec2((float(a) + 0.5f) / kBuriedProbesPerAxis, (float(b) + 0.5f) / kBuriedProbesPerAxis));
            ray.direction = d.x * tangent + d.y * bitangent + d.z * r.normal;
            Hit hit;
            const int traced = a * kBuriedProbesPerAxis + b + 1;
            if (intersectClosest(bvh, ray, hit)) {
                const vec3* n = scene.normals + 3 * size_t(hit.triangle);
                const vec3 normal = (1.0f - hit.b1 - hit.b2) * n[0] + hit.b1 * n[1] + hit.b2 * n[2];
                if (glm::dot(normal, ray.direction) > 0.0f) ++fromBehind;
            }
            // The majority is decided once either side holds half the rays.
            if (2 * fromBehind > kBuriedProbeRays) return true;
            if (2 * (traced - fromBehind) >= kBuriedProbeRays) return false;
        }
    return 2 * fromBehind > kBuriedProbeRays;
}

// Where a receiver sample that no gather point applies to looks its indirect light up. A
// sample near the line where its surface meets another (a wall's texel by the floor) lies
// within the other surface's voxel layer or beside it: lifted off its own surface
// (liftOffSurface) it is still in that layer or within the trilinear reach of it, every path
// from there to a gather point runs along the layer and is blocked, and the cones it then
// gathers itself start inside the layer's opacity and see nothing: a dark line of texels along
// a room's edges (docs/accuracy.md, "Samples along a room's edges"). Such a sample tries the
// centres of the free voxels (α < ½) of the 3 × 3 × 3 around its lifted point that do not lie
// behind its own surface and lie in front of the surfaces between: a ray from the centre back
// to the sample meets nothing before it, and what it meets there it meets from the front.
// Nearest first (ties: z, y, x order), it moves where its lifted point is that centre; `moved`
// holds the moved positions, and the count is returned.
constexpr int kLookupCandidates = 27;
VL_HOSTDEV inline int lookupCandidates(const TraceSceneView& scene, const BvhView& bvh, const MipView& mips,
                                       const SurfaceSample& r, vec3 (&moved)[kLookupCandidates]) {
    if (mips.levelCount == 0 || !mips.levels[0].index) return 0;
    const MipLevelView& occupancy = mips.levels[0];
    const float h = mips.voxelSize;
    const vec3 lifted = liftOffSurface(r.position, r.normal, h);
    const vec3 centre = glm::floor(lifted / h + vec3(0.5f));
    const nanovdb::Coord voxel(int(centre.x), int(centre.y), int(centre.z));
    const vec3 target = offsetRayOrigin(r.position, r.normal, bvh.extent);
    IndexLeafCache leaves;
    float distances[kLookupCandidates];
    int count = 0;
    for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const vec3 step = vec3(float(dx), float(dy), float(dz));
                if (glm::dot(step, r.normal) < 0.0f) continue;
                if (blocksPath(occupancy, leaves, voxel + nanovdb::Coord(dx, dy, dz))) continue;
                const vec3 candidate = (centre + step) * h;
                const vec3 toSample = target - candidate;
                const float length = glm::length(toSample);
                if (length > 0.0f) {
                    Ray ray;
                    ray.origin = candidate;
                    ray.direction = toSample / length;
                    ray.tMax = 1.01f * length;
                    Hit hit;
                    if (!intersectClosest(bvh, ray, hit) || hit.t < 0.99f * length) continue;
                    if (!(glm::dot(windingCross(scene, hit.triangle), ray.direction) < 0.0f)) continue;
                }
                // Insertion by distance keeps the nearest first and equal ones in loop order.
                const float distance = glm::dot(candidate - lifted, candidate - lifted);
                int k = count++;
                for (; k > 0 && distances[k - 1] > distance; --k) {
                    distances[k] = distances[k - 1];
                    moved[k] = moved[k - 1];
                }
                distances[k] = distance;
                moved[k] = r.position + (candidate - lifted);
            }
    return count;
}

struct ElementLighting {
    vec3 direct{0.0f};
    vec3 indirect{0.0f};
    vec3 directRadiance{0.0f};
    vec3 indirectRadiance{0.0f};
    float openWeight = 0.0f;  // of the samples not buried
};

// The irradiance at a surface point from n × n cosine-distributed rays (a gather point's fan,
// fan_rays.h, laid out in the frame `tangent` turned by `turn`), each reading the
// level-0 texels of `mips` where it hits (fan_rays.h): how a receiver sample that no gather
// point applies to gathers when the points gathered by rays. Level 0 is all it reads, so the
// mips need no coarser levels then.
VL_HOSTDEV inline vec3 rayGatherAtSample(const TraceSceneView& scene, const BvhView& bvh, const MipView& mips,
                                         const vec3& position, const vec3& normal, const vec3& tangent, float turn,
                                         int raysPerAxis) {
    if (mips.levelCount <= 0 || raysPerAxis <= 0) return vec3(0.0f);
    const Level0Texels level0(mips.levels[0]);
    const FanFrame frame = fanFrame(normal, tangent, turn);
    Ray ray;
    ray.origin = offsetRayOrigin(position, normal, bvh.extent);
    IndexLeafCache leaves;
    vec3 sum(0.0f);
    for (int i = 0; i < raysPerAxis; ++i)
        for (int j = 0; j < raysPerAxis; ++j) {
            ray.direction = inFrame(frame, fanDirection(i, j, raysPerAxis));
            Hit hit;
            if (!intersectClosest(bvh, ray, hit)) continue;
            readHitTexels(level0, leaves, ray.at(hit.t), ray.direction, windingCross(scene, hit.triangle),
                          [&](int32_t voxel, int travel, float weight) { sum += weight * level0.colour(voxel, travel); });
        }
    return sum * (kPi / float(raysPerAxis * raysPerAxis));
}

// Indirect irradiance at a receiver sample: interpolated from the gather points of `cache`
// (irradiance_cache.h), or, without a cache or where no gather point applies, gathered by
// cones (by rays where the points were: rayGatherAtSample), laid out in the frame that turns
// with the scene (gatherFrame) and turned by
// coneTurn(seed) (a texel's or pixel's index, which the scene's placement does not change).
// Where no gather point applies the sample first moves out of another surface's voxel layer
// (lookupCandidates) and tries the gather points from there; only such samples move.
VL_HOSTDEV inline vec3 indirectIrradiance(const TraceSceneView& scene, const BvhView& bvh, const MipView& mips,
                                          const IrradianceCacheView* cache, const ConeSet& set,
                                          const ConeSettings& cone, const SurfaceSample& sample, uint64_t seed) {
    vec3 E;
    if (cache && interpolateIrradiance(*cache, sample.position, sample.normal, E)) return E;
    vec3 moved[kLookupCandidates];
    const int count = lookupCandidates(scene, bvh, mips, sample, moved);
    if (cache)
        for (int k = 0; k < count; ++k)
            if (interpolateIrradiance(*cache, moved[k], sample.normal, E)) return E;
    const vec3 position = count > 0 ? moved[0] : sample.position;
    vec3 tangent;
    float positionTurn;
    gatherFrame(position, sample.normal, mips.centre(), mips.voxelSize, tangent, positionTurn);
    if (cache && cache->raysPerAxis > 0) {
        // A moved sample's rays start at the voxel centre it was found to be seen from (its
        // lifted point); moved[0] itself lies up to half a voxel below its own surface.
        const vec3 origin =
            count > 0 ? moved[0] + (liftOffSurface(sample.position, sample.normal, mips.voxelSize) - sample.position)
                      : sample.position;
        return rayGatherAtSample(scene, bvh, mips, origin, sample.normal, tangent, coneTurn(seed), cache->raysPerAxis);
    }
    return coneTraceIrradiance(mips, position, sample.normal, set, cone, nullptr, coneTurn(seed), &tangent);
}

// Samples [first, last) of `samples`; a sample's index seeds its direct term's strata and
// turns its cone set (coneTurn), so the sub-samples of one pixel average differently turned
// sets. `mips` null: no indirect light. `cache`: where indirect light is interpolated from (null:
// every sample gathers its own). `mayBeBuried`: lightmap texels, which can lie inside closed
// geometry (isBuried: then no indirect light either); camera hits are seen, so never buried.
VL_HOSTDEV inline ElementLighting shadeReceiverElement(const TraceSceneView& scene, const BvhView& bvh,
                                                       const MipView* mips, const IrradianceCacheView* cache,
                                                       const ConeSet& set, const ConeSettings& cone,
                                                       const DirectLightSettings& direct, const SurfaceSample* samples,
                                                       uint32_t first, uint32_t last, bool mayBeBuried) {
    ElementLighting out;
    for (uint32_t i = first; i < last; ++i) {
        const SurfaceSample& r = samples[i];
        const vec3 ed = directIrradiance(scene, bvh, r, direct, i) * kInvPi;
        const bool buried = mips && mayBeBuried && !(maxComponent(ed) > 0.0f) && isBuried(scene, bvh, r);
        const vec3 ei = mips && !buried ? indirectIrradiance(scene, bvh, *mips, cache, set, cone, r, i) * kInvPi : vec3(0.0f);
        out.direct += r.weight * ed;
        out.indirect += r.weight * ei;
        out.directRadiance += r.weight * r.albedo * ed;
        out.indirectRadiance += r.weight * r.albedo * ei;
        if (!buried) out.openWeight += r.weight;
    }
    return out;
}

}  // namespace vl
