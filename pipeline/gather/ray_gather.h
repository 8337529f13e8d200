// The gather by rays: takes gather points (gather/irradiance_cache.h), the radiance mips, the
// BVH and the traced scene; gives the irradiance at each point from n × n rays against the
// scene's triangles, each reading the light of the voxels where it hits (direct light and every
// earlier bounce). The rays only decide which voxels a point sees.
//
// Why rays, not cones: a cone reads a coarse mip voxel as partly opaque wherever a wall lies
// within its trilinear footprint, so walls seen edge-on are a fog, a block beside a cone's path
// dims it, and its far samples reach through a wall into the room behind. A ray finds the
// surface it sees exactly and reads only the voxels that surface passes through
// (docs/decisions.md, "Rays for visibility" and "Where the Cornell boxes' indirect error comes
// from"). Where the rays would see the backs of single-sided surfaces, which the voxels do not
// show, the bake gathers by cones instead (probeSingleSidedBacks below).
#pragma once

#include "gather/fan_rays.h"
#include "gather/gather_visibility.h"
#include "gather/bounces.h"
#include "gather/irradiance_cache.h"
#include "cone/radiance_mips.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"

#include <string>
#include <vector>

namespace vl {

class Progress;

// How deep a near field's path goes before it reads the voxels (FanExtras::nearField).
inline constexpr int kNearFieldBounces = 4;

// E at every point (W/m²) from raysPerAxis² rays (1 … kMaxGatherRaysPerAxis, else
// SettingsError).
//
// A ray leaves the point's surface: from the point lifted off its surface (liftOffSurface), a
// ray back along −n finds the surface within three voxels, and the rays start on it (offset by
// offsetRayOrigin); where none is found they start at the lifted point. The n × n directions
// are cosine-distributed and stratified, turned about the normal by the point's frame
// (gatherFrame), so a point's rays turn with the scene. Where a ray hits a surface of normal n
// it reads, along each axis a (weight n_a²), the level-0 texel that shows the face looking back
// at it (radiance_mips.h) in the voxel holding the hit or its neighbour along a, whichever shows
// more surface (fan_rays.h readHitTexels). Only voxels the surface passes through are read: a
// coarser level around the hit let far rays read a lit floor across a wall. A ray that leaves
// the scene reads nothing: it sees the sky, which the bounces count as direct light
// (FaceTransport::open) and the receivers trace on their own (lighting/direct_light.h).
//
// A ray finds the voxels and faces it reads in the level 0 of `mips` (its index and the
// texels' coverage: where surface is, which does not change with the light) and reads their
// light in `faces`, one per voxel of those mips (the voxels' faceRadiance, or a part of it:
// the bake's final gather reads the light without its bright patches). TBB-parallel over
// points; the same bytes at any thread count. `progress` advances once per point.
std::vector<vec3> gatherByRays(const std::vector<GatherPoint>& points, const MipView& mips,
                               const std::vector<FaceRadiance>& faces, const BvhView& bvh, const TraceSceneView& scene,
                               int raysPerAxis, Progress* progress = nullptr);

// Where a fan of rays starts (on its surface, offset off it: trace/ray_offset.h) and the frame
// its n × n directions are laid out in (fan_rays.h).
struct FanStart {
    vec3 origin{0.0f};
    FanFrame frame{};
    uint64_t seed = 0;  // the image sky's draws: a fan's own, so its light does not depend on the fans beside it
    vec2 jitter{-1.0f};  // ≥ 0: its rays at this point of their strata (fan_rays.h fanDirectionJittered); else the fixed fan
};

// How a fan's irradiance (RGB) changes as its normal turns, from the same rays (Ward and
// Heckbert 1992's rotation gradient): E(n + ν) ≈ E + G ν for a small change ν of the normal
// in the fan's tangent plane; column j of G is ∂E/∂n_j (world axes). Turning the normal by ν
// changes E = ∫ L cos θ dω by ∫ L (ν·ω) dω, each stratum's π/n² share times ν · its mean of
// ω_t / cos θ (fanTurnWeights). `light` is of the light the rays read, `sky` of the sky the
// rays that leave see (a uniform sky's or the image's radiance along them).
struct RotationGradients {
    glm::mat3 light{0.0f}, sky{0.0f};
};

// Per stratum of an n × n fan (ray k = i·n + j, fan_rays.h), the mean over it of d / cos θ, d
// its points on the cosine-weighted disk, in the fan's frame (tangent, bitangent). The mean,
// not its ray's direction: 1/cos θ grows without bound towards the horizon, so the outer ring's
// mean direction undercounts it (tests/bake/ray_gather_test.cpp, docs/accuracy.md).
std::vector<vec2> fanTurnWeights(int n);

// What a fan's rays found besides the light they read: the sky's irradiance through the rays
// that left the scene (a uniform sky's radiance on their π/n² each; under an image sky each
// ray's share against skyDrawsPerAxis² draws from the image, and those draws:
// lighting/direct_light.h skyShare), the variance of the estimate of the irradiance both give
// (mean channel), from the spread of the rays' radiance, and the rays that left the scene.
struct FanExtras {
    bool readSky = true;  // set by the caller: false leaves the sky out of `sky` and `variance`
    // Set by the caller (hit-light exact): the lights' own first reflection within `faces`
    // (lighting/surface_light.h punctualFaceRadiance). Each hit reads the faces less it and
    // takes the lights' reflection at the hit point by a shadow ray: a shaded point no longer
    // reads the sunlit surface that shares its voxel.
    const std::vector<FaceRadiance>* lightsAtHits = nullptr;
    // Set by the caller (near field): a hit nearer than this (world units; 0: none) does not
    // read its voxel, which holds a crease and the open surface beside it as one face. Its
    // light is traced on: its emission seen from a bounce, its lights by a shadow ray (with
    // lightsAtHits), and its albedo times the light one cosine ray from it brings back, by the
    // same rule, at most kNearFieldBounces deep, then from the voxels. Needs `faces` to hold
    // all the light but the lights' (no bright patches split off).
    float nearField = 0.0f;
    // Set by the caller: also each fan's rotation gradients (RotationGradients).
    bool rotationGradients = false;
    // Rays of the fans that went on at a near hit, and the further rays they traced.
    uint64_t nearHits = 0, nearRays = 0;
    std::vector<vec3> sky;
    std::vector<float> variance;
    std::vector<uint32_t> escaped;
    std::vector<RotationGradients> rotation;  // with rotationGradients
};

// gatherByRays from fans given directly (a lightmap texel's, gather/texel_gather.h); `extras`,
// when given, receives the sky and the variance per fan. The same bytes at any thread count;
// `progress` advances once per fan.
std::vector<vec3> gatherFans(const std::vector<FanStart>& fans, const MipView& mips,
                             const std::vector<FaceRadiance>& faces, const BvhView& bvh, const TraceSceneView& scene,
                             int raysPerAxis, Progress* progress = nullptr, FanExtras* extras = nullptr,
                             int skyDrawsPerAxis = 0);

// The same gather as a fixed map from the voxels' face light to the points' irradiance
// (gather/bounces.h FaceTransport): which faces a point's rays read, and how much, depends on
// where surface is, not on the light, so the bounces trace once and apply the map at every
// bounce, and the final gather, when it sends as many rays from the same points, applies it
// once more (gather.cpp; docs/decisions.md, "Rays for visibility").
// Applied to faces it gives gatherByRays with the same faces, up to the order of summing.
// TBB-parallel over points; the same bytes at any thread count. `progress` advances once per
// point. `voxelCount`: the voxels of `mips` (faceRadiance's size). Under an image sky
// (scene.sky) with `skyDrawsPerAxis` > 0 the rays that leave the scene also give
// FaceTransport::skyCosine, to join skyImageDrawsAtPoints' draws.
FaceTransport rayTransport(const std::vector<GatherPoint>& points, const MipView& mips, size_t voxelCount,
                           const BvhView& bvh, const TraceSceneView& scene, int raysPerAxis, int skyDrawsPerAxis = 0,
                           Progress* progress = nullptr);

// Per point, where its rays start (the surface under it, as gatherByRays finds it): where the
// final gather adds its bright patches' light from (gather/bright_patches.h).
std::vector<vec3> fanOrigins(const std::vector<GatherPoint>& points, float voxelSize, const BvhView& bvh,
                             const TraceSceneView& scene);

// Per point, the weight of its rays (raysPerAxis² as gatherByRays sends them) that leave the
// scene: irradiance per unit radiance of a uniform sky, π where nothing blocks it
// (FaceTransport::open, for the bounces when they gather by cones).
std::vector<float> skyOpenness(const std::vector<GatherPoint>& points, float voxelSize, const BvhView& bvh,
                               const TraceSceneView& scene, int raysPerAxis);

// Per point, the sky's irradiance where its rays start (rayFan), by the receivers' estimate
// (lighting/direct_light.h skyIrradiance, `strata`² directions of each kind, seeded by the
// point's index): for the bounces under a sky with an image, whose light is not one
// radiance times an openness.
std::vector<vec3> skyIrradianceAtPoints(const std::vector<GatherPoint>& points, float voxelSize, const BvhView& bvh,
                                        const TraceSceneView& scene, int strata);
// Only its image draws' part (lighting/direct_light.h skyImageDrawsIrradiance: `drawsPerAxis`²
// draws against `raysPerAxis`² cosine rays), for the bounces when a FaceTransport's rays give
// the rest (FaceTransport::skyCosine).
std::vector<vec3> skyImageDrawsAtPoints(const std::vector<GatherPoint>& points, float voxelSize, const BvhView& bvh,
                                        const TraceSceneView& scene, int drawsPerAxis, int raysPerAxis);

struct BackProbe {
    uint64_t hits = 0;              // rays that hit a triangle
    uint64_t singleSidedBacks = 0;  // of them, on the back of a single-sided material
    double share() const { return hits > 0 ? double(singleSidedBacks) / double(hits) : 0.0; }
};

// What share of the rays from `points` (raysPerAxis² each, as gatherByRays sends them) hit
// the back of a single-sided surface, the part of a scene the voxels do not show. The mips show
// a surface's front, and a double-sided surface's back; a path tracer (and Cycles) reflects
// light off both sides of every surface. Where rays see many such backs they lose light at every
// bounce, where the blur of cones keeps some, so the bake gathers by cones there
// (gather_visibility.h; docs/decisions.md, "Where the voxels cannot answer a ray").
BackProbe probeSingleSidedBacks(const std::vector<GatherPoint>& points, float voxelSize, const BvhView& bvh,
                                const TraceSceneView& scene, int raysPerAxis);

struct GatherVisibilityChoice {
    GatherVisibility visibility = GatherVisibility::Cones;
    std::string setBy;  // why: the setting, or the probe's share against the limit
    BackProbe probe;    // hits == 0 when no probe ran
};

// `requested` when it is cones or rays; for auto, the probe from `points` (the bounces'
// gather points).
GatherVisibilityChoice chooseGatherVisibility(GatherVisibility requested, const IrradianceCache& points,
                                              const BvhView& bvh, const TraceSceneView& scene);
// One line for the progress output: "gather visibility: rays (…)".
std::string describeGatherVisibility(const GatherVisibilityChoice& choice);

}  // namespace vl
