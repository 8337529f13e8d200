// Further bounces inside the voxel grid: takes a lit VoxelScene (faceRadiance: the light each
// voxel face reflects from the lights, the lighting stage's output) and gives the same scene
// with faceRadiance and radiance holding `bounces` more diffuse interreflections, gathered at
// the gather points of an IrradianceCache (irradiance_cache.h) by cones or by rays and
// interpolated at every voxel side.
//
// Why gather points: bounce light is smooth, so a gather per point costs a fraction of a
// gather per voxel for the same error (docs/decisions.md, "Gather points"). TBB-parallel over
// voxels; each voxel's value depends only on the previous bounce's light, so the result is the
// same bytes at any thread count.
#pragma once

#include "cone/cone_trace.h"
#include "gather/irradiance_cache.h"
#include "voxel/voxel_scene.h"

#include <vector>

namespace vl {

class Progress;

// Irradiance at each face of a voxel (propagateBounces): faces of one side get that side's E,
// faces without surface zero. axisWeights: +X, −X, +Y, −Y, +Z, −Z. `turn`: the cone set's
// rotation about each side's normal.
VL_HOSTDEV inline void faceIrradiance(const MipView& mips, const vec3& centre, const vec3& normal,
                                      const float* axisWeights, const ConeSet& set, const ConeSettings& settings,
                                      vec3 (&faces)[6], float turn = 0.0f) {
    const VoxelSides sides = voxelSides(normal, axisWeights);
    vec3 gathered[6];
    for (int s = 0; s < sides.count; ++s)
        gathered[s] = coneTraceIrradiance(mips, centre, sides.normal[s], set, settings, nullptr, turn);
    for (int f = 0; f < 6; ++f) faces[f] = sides.sideOfFace[f] >= 0 ? gathered[sides.sideOfFace[f]] : vec3(0.0f);
}

// What follows the last bounce.
enum class BounceTail {
    None,         // L_bounces: exactly that many bounces
    Geometric,    // L_bounces plus the series' geometric tail, ΔL·r/(1 − r), r each face's own
                  // ratio of its last two increments, capped by the scene's (bounces.cpp)
};

// Irradiance at points as a fixed linear map of the voxels' face radiance: E[q] = Σ weight ·
// faceRadiance[slot / 6][slot % 6] over q's entries. A gather whose visibility does not
// change between bounces is found once and applied at each.
struct FaceTransport {
    struct Entry {
        uint32_t slot;  // voxel · 6 + face
        float weight;
    };
    std::vector<uint32_t> begin{0};  // point q: entries [begin[q], begin[q + 1])
    std::vector<Entry> entries;
    // Per point, the weight of its rays that leave the scene: irradiance per unit radiance of
    // a uniform sky (π where nothing blocks it). Empty where the builder does not know it.
    std::vector<float> open;
    // Per point, an image sky's light through those rays, each an image sky's share against
    // the image draws that join them (lighting/direct_light.h skyShare). Empty without an image sky.
    std::vector<vec3> skyCosine;
    size_t pointCount() const { return begin.size() - 1; }
};

// E at every point of `transport` from `faces` (TBB-parallel; each point summed in entry
// order: the same bytes at any thread count). Throws Error when a slot lies past `faces`.
std::vector<vec3> applyTransport(const FaceTransport& transport, const std::vector<FaceRadiance>& faces);

struct GatherScene;

struct BounceSettings {
    int bounces = 0;  // 0 … 1024 (SettingsError outside): 0 leaves the voxels as they are
    int gatherLevel = 2;  // the gather points' cell level, 0 … 16
    BounceTail tail = BounceTail::None;  // BounceTail::Geometric needs bounces ≥ 2
    ConeSettings cone;  // the cones, where the points gather by cones
    // The points see by n × n rays against the triangles (gather/ray_gather.h rayTransport,
    // traced once), not by cones. raysPerAxis also sets the rays that tell how open a point
    // is to a uniform sky (skyOpenness).
    bool byRays = false;
    int raysPerAxis = 14;
    int skyDrawsPerAxis = 0;  // an image sky's draws per axis (lighting/direct_light.h)
    // The sky lights the voxels' surfaces before the first bounce, interpolated to their sides
    // as the bounces' irradiance is (false where the voxel pass already lit them by it).
    bool skyLit = false;
};

// What the bounces leave besides the voxels' light, for the final gather to take on.
struct Bounced {
    // The result's radiance mips (RadianceMips::relight: the same bytes as buildRadianceMips of
    // the result); by rays level 0 alone (RadianceMips::addParentLevels adds the rest). Empty
    // when bounces = 0.
    RadianceMips mips;
    IrradianceCache points;  // the gather points at gatherLevel, linked over `mips`
    // By rays, the points' rays as one map (the cache's points, then one per side no point
    // applies to): a final gather from the same points with as many rays applies it again.
    FaceTransport transport;
};

// Jacobi on the rendering equation, every light path counted once, per face:
//   L_0 = faceRadiance as lit;  L_b = L_0 + albedo/π · E_side[L_{b−1}],
// E_side[L] the irradiance at the surface side the face belongs to. Adding to the previous
// bounce's radiance instead of L_0 would count the earlier bounces twice. In a closed box of
// albedo ρ and uniform L_0: L_1 = (1 + ρ)·L_0, L_2 = (1 + ρ + ρ²)·L_0.
//
// Irradiance is gathered at the gather points, one per surface side of each block of 2^L voxels
// per axis, by cones through the mips or by rays against the triangles (a FaceTransport traced
// once and applied at every bounce), and every voxel side takes the interpolation of the points
// around it that face its way (voxel_scene.h voxelSides). A side's light is reflected by that
// side's faces only, so a thin wall lit on one side does not pass it to the other. A side no
// gather point applies to (an isolated sliver) gathers at the voxel's centre itself; a voxel
// without axis weights has no surface. Without faceRadiance (a scene lit elsewhere, synthetic
// tests) every face with a surface starts from `radiance`.
//
// Replaces voxels.faceRadiance and voxels.radiance with L_bounces (and its tail). Rays and the
// sky need `scene`, what the rays meet; without it the bounces go by cones and no sky lights
// them. `points`: the gather points of these voxels at settings.gatherLevel, made before (the
// bake's, placed by rays and probed for the visibility: gather/gather.h), taken instead of
// being built again; empty, they are built here. `progress` advances by the voxel count once
// per bounce. Throws SettingsError for settings out of range, Error when radiance,
// faceRadiance (when present), albedo, normal or axisWeights do not match the voxel count.
Bounced propagateBounces(VoxelScene& voxels, const BounceSettings& settings, const GatherScene* scene = nullptr,
                         IrradianceCache points = IrradianceCache(), Progress* progress = nullptr);

}  // namespace vl
