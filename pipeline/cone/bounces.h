// Further bounces inside the voxel grid: takes a lit VoxelScene (faceRadiance = the light
// each voxel face reflects from the lights, the lighting stage's output), gives the same
// scene with faceRadiance and radiance including `bounces` more diffuse interreflections.
//
// Iteration (Jacobi on the rendering equation, every light path counted once), per face:
//   L_0 = faceRadiance as lit;  L_b = L_0 + albedo/π · E_side[L_{b−1}],
// E_side[L] the irradiance at the surface side the face belongs to, cone-traced from the
// directional mips of L, or a fixed map of L's faces (FaceTransport, below) that rays against
// the triangles found once. Adding to the previous bounce's radiance instead of L_0 would count
// the earlier bounces twice. In a closed box of albedo ρ and uniform L_0:
// L_1 = (1 + ρ)·L_0, L_2 = (1 + ρ + ρ²)·L_0.
//
// Where a voxel gathers: irradiance is cone-traced at the gather points of an
// IrradianceCache (irradiance_cache.h) at cell level gatherLevel, one per surface side of
// each block of 2^L voxels per axis, and every voxel side takes the interpolation of the
// points around it that face its way (a voxel's surface sides: voxel_scene.h voxelSides;
// the front n, the back −n of a double-sided surface, where normals cancel each face with a
// surface along its own axis). The light a side gathers is reflected by that side's faces
// only, so a thin wall lit on one side does not pass it to the other. A side no gather point
// applies to (an isolated sliver) gathers at the voxel's centre itself. A voxel without
// axis weights has no surface: it gathers and shows nothing. Why gather points: bounce
// light is smooth, and the Cycles Cornell boxes show the same lightmap error with the
// bounces gathered at level-3 points as at every voxel (quad 5.82% / 5.84%, point 7.56% /
// 7.62%) in a thirtieth of the time (0.3 s against 11 s on 2 cores: the bounces stage in
// bake.json of `build/voxlight bake ../shared/reference/cornell_quad.gltf`, before and after).
//
// Without faceRadiance (a scene lit elsewhere, synthetic tests) every face with a surface
// starts from `radiance`.
//
// TBB-parallel over voxels; each voxel's value depends only on the previous bounce's mips,
// so the result is the same bytes at any thread count.
#pragma once

#include "cone/cone_trace.h"
#include "cone/irradiance_cache.h"
#include "voxel/voxel_scene.h"

#include <functional>
#include <vector>

namespace vl {

class Progress;

// Irradiance at each face of a voxel (see above): faces of one side get that side's E,
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

// Replaces voxels.faceRadiance and voxels.radiance with L_bounces (and its tail, which needs
// bounces ≥ 2: the ratio of the last two). bounces = 0 leaves them unchanged. Throws
// SettingsError for bounces < 0 or > 1024, a gather level outside 0..16 or invalid settings,
// Error when radiance, faceRadiance (when present), albedo, normal, axisWeights, opacity or
// solid do not match the voxel count. `progress`, when given, advances by the voxel count
// once per bounce. `mips`, when given and bounces > 0, receives the radiance mips of the
// result: the bounces' own mips relit, the same bytes as buildRadianceMips(voxels) afterwards
// (RadianceMips::relight), without building the levels and index grids a second time; by a
// transport (rays, which read level 0 alone) level 0 alone, as buildLevelZeroMips gives it
// (RadianceMips::addParentLevels adds the rest).
// `cache`, likewise, receives the bounces' gather points at gatherLevel, linked over those
// mips (the topology a final gather at the same level builds and links again); when it
// already holds points at gatherLevel (the caller's, of these voxels: the bake probes them
// first, bake/gather_visibility.h), the bounces take them instead of building them again.
// `transport`, when given, replaces the cones: it maps the gather points (the cache's, then
// one per side no point applies to, at the voxel's centre) to a FaceTransport built once
// (bake/ray_gather.h rayTransport: rays against the triangles), which it owns and keeps past
// the call (the bake's final gather applies it again), and every bounce applies it to the
// last bounce's faceRadiance; the mips are then only relit for `mips`. `sky`, when given
// with a radiance, lights the voxels' surfaces before the first bounce (BounceSky).
//
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

// The sky for the bounces (scene.h Sky): what the voxels' surfaces receive from it joins
// their direct light before the first bounce, interpolated to the voxels' sides as the
// bounces' irradiance is. At every gather point that is, for a uniform sky, radiance × the
// point's openness (a FaceTransport's `open`, else `openness` of the points); for a sky with
// an image, `irradiance` of the points (the receivers' estimate, lighting/direct_light.h), or,
// where the transport's rays already hold their part (FaceTransport::skyCosine), those plus
// `imageDraws` of the points.
struct BounceSky {
    using PerPoint = std::function<std::vector<vec3>(const std::vector<GatherPoint>& points)>;
    vec3 radiance{0.0f};
    std::function<std::vector<float>(const std::vector<GatherPoint>& points)> openness;
    PerPoint irradiance;  // null: uniform
    PerPoint imageDraws;
};
// E at every point of `transport` from `faces` (TBB-parallel; each point summed in entry
// order: the same bytes at any thread count). Throws Error when a slot lies past `faces`.
std::vector<vec3> applyTransport(const FaceTransport& transport, const std::vector<FaceRadiance>& faces);
using TransportBuilder =
    std::function<const FaceTransport&(const std::vector<GatherPoint>& points, const MipView& mips)>;
void propagateBounces(VoxelScene& voxels, const ConeSettings& settings, int bounces, int gatherLevel,
                      BounceTail tail, Progress* progress = nullptr, RadianceMips* mips = nullptr,
                      IrradianceCache* cache = nullptr, const TransportBuilder* transport = nullptr,
                      const BounceSky* sky = nullptr);

}  // namespace vl
