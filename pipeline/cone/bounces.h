// Further bounces inside the voxel grid: takes a lit VoxelScene (faceRadiance = the light
// each voxel face reflects from the lights, the lighting stage's output), gives the same
// scene with faceRadiance and radiance including `bounces` more diffuse interreflections.
//
// Iteration (Jacobi on the rendering equation, every light path counted once), per face:
//   L_0 = faceRadiance as lit;  L_b = L_0 + albedo/π · E_side[L_{b−1}],
// E_side[L] the cone-traced irradiance at the surface side the face belongs to, from the
// directional mips of L. Adding to the previous bounce's radiance instead of L_0 would count
// the earlier bounces twice. In a closed box of albedo ρ and uniform L_0:
// L_1 = (1 + ρ)·L_0, L_2 = (1 + ρ + ρ²)·L_0.
//
// Where a voxel gathers: once per surface side (voxel_scene.h voxelSides), cones around the
// side's normal from the voxel's centre: the front n; the back −n of a double-sided surface;
// where normals cancel (a thin wall, a closed sliver) each face with a surface along its own
// axis. The light a side gathers is reflected by that side's faces only, so a thin wall lit
// on one side does not pass it to the other. A voxel without axis weights has no surface:
// it gathers and shows nothing.
//
// Without faceRadiance (a scene lit elsewhere, synthetic tests) every face with a surface
// starts from `radiance`.
//
// TBB-parallel over voxels; each voxel's value depends only on the previous bounce's mips,
// so the result is the same bytes at any thread count.
#pragma once

#include "cone/cone_trace.h"
#include "voxel/voxel_scene.h"

namespace vl {

class Progress;

// Irradiance at each face of a voxel (see above): faces of one side get that side's E,
// faces without surface zero. axisWeights: +X, −X, +Y, −Y, +Z, −Z. `turn`: the cone set's
// rotation (coneTurn of the voxel's index in propagateBounces).
VL_HOSTDEV inline void faceIrradiance(const MipView& mips, const vec3& centre, const vec3& normal,
                                      const float* axisWeights, const ConeSet& set, const ConeSettings& settings,
                                      vec3 (&faces)[6], float turn = 0.0f) {
    const VoxelSides sides = voxelSides(normal, axisWeights);
    vec3 gathered[6];
    for (int s = 0; s < sides.count; ++s)
        gathered[s] = coneTraceIrradiance(mips, centre, sides.normal[s], set, settings, nullptr, turn);
    for (int f = 0; f < 6; ++f) faces[f] = sides.sideOfFace[f] >= 0 ? gathered[sides.sideOfFace[f]] : vec3(0.0f);
}

// Replaces voxels.faceRadiance and voxels.radiance with L_bounces. bounces = 0 leaves them
// unchanged. Throws SettingsError for bounces < 0 or > 1024 or invalid settings, Error when
// radiance, faceRadiance (when present), albedo, normal, axisWeights, opacity or solid do not
// match the voxel count. `progress`, when given, advances once per voxel and bounce.
void propagateBounces(VoxelScene& voxels, const ConeSettings& settings, int bounces, Progress* progress = nullptr);

}  // namespace vl
