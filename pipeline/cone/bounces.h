// Further bounces inside the voxel grid: takes a lit VoxelScene (radiance = the light each
// voxel reflects from the lights, the lighting stage's output), gives the same scene with
// radiance including `bounces` more diffuse interreflections.
//
// Iteration (Jacobi on the rendering equation, every light path counted once):
//   L_0 = radiance as lit;  L_b = L_0 + albedo/π · E[L_{b−1}],
// E[L] the cone-traced irradiance at each voxel from the mips of L. Adding to the previous
// bounce's radiance instead of L_0 would count the earlier bounces twice. In a closed box of
// albedo ρ and uniform L_0: L_1 = (1 + ρ)·L_0, L_2 = (1 + ρ + ρ²)·L_0.
//
// Where a voxel gathers: cones around its normal from its centre. Where its normals cancel
// (normal zero: a two-sided thin wall, a closed sliver) it gathers the hemisphere of each
// signed axis face with a non-zero axis weight and takes their mean weighted by the axis
// weights — the six-axis rule the lighting stage uses for direct light, so both sides of a
// thin wall receive indirect light. A voxel with no normal and no axis weights gathers
// nothing.
//
// TBB-parallel over voxels; each voxel's value depends only on the previous bounce's mips,
// so the result is the same bytes at any thread count.
#pragma once

#include "cone/cone_trace.h"
#include "voxel/voxel_scene.h"

namespace vl {

// Irradiance a voxel receives (see above). axisWeights: +X, −X, +Y, −Y, +Z, −Z.
VL_HOSTDEV inline vec3 voxelIrradiance(const MipView& mips, const vec3& centre, const vec3& normal,
                                       const float* axisWeights, const ConeSet& set, const ConeSettings& settings) {
    if (glm::length(normal) >= 0.5f) return coneTraceIrradiance(mips, centre, normal, set, settings);
    vec3 sum(0.0f);
    float weightSum = 0.0f;
    for (int face = 0; face < 6; ++face) {
        const float w = axisWeights[face];
        if (!(w > 0.0f)) continue;
        vec3 axis(0.0f);
        axis[face / 2] = (face % 2 == 0) ? 1.0f : -1.0f;
        sum += w * coneTraceIrradiance(mips, centre, axis, set, settings);
        weightSum += w;
    }
    return weightSum > 0.0f ? sum / weightSum : vec3(0.0f);
}

// Replaces voxels.radiance with L_bounces. bounces = 0 leaves it unchanged. Throws
// SettingsError for bounces < 0 or > 1024 or invalid settings, Error when radiance, albedo,
// normal, axisWeights, opacity or solid do not match the voxel count.
void propagateBounces(VoxelScene& voxels, const ConeSettings& settings, int bounces);

}  // namespace vl
