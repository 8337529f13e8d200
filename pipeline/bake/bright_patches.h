// Bright patches: the final gather's split of the voxels' light into a few bright patches,
// gathered at every gather point with shadow rays against the triangles, and the diffuse rest
// that the cones gather from the mips or the rays read from the voxels. Takes the lit voxels (after the bounces) and gives the
// patches and the rest's face radiance; then adds the patches' irradiance at gather points.
//
// Why: a cone reads a level of the mips one voxel wide to every side of its axis, so a small
// bright region (the floor under a ceiling light, a point light's hot spot on the ceiling) is
// seen too much by the cones whose axis passes near it and not at all by the others, and its
// blur lets it through the edges of the objects in front of it. Measured by
// `build/accuracy/accuracy_transport --hot 8` on the Cycles Cornell boxes: with the brightest
// faces gathered by rays the ceiling of the quad box gathers 1.00 of the rays' first bounce
// instead of 1.16, the floor of the point box 0.89 instead of 0.70.
//
// A face is bright when its radiance exceeds `factor` times the area-weighted mean of all
// faces; bright faces are merged per cell of `cellVoxels`³ voxels and surface side (the
// signed axis its normal is closest to: voxel_scene.h voxelSides) into one patch each (its
// power, area, normal and power-weighted surface point; a side's area is |Σ w_f·d_f| of its
// faces, along its normal); the `maxPatches` most powerful patches are taken out of the mips,
// the others stay in them.
#pragma once

#include "cone/irradiance_cache.h"
#include "trace/bvh.h"
#include "voxel/voxel_scene.h"

#include <vector>

namespace vl {

struct BrightPatch {
    vec3 position{0.0f};  // local frame, metres: the power-weighted surface point of its faces
    vec3 normal{0.0f};    // unit: the area-weighted normal of its sides
    float area = 0.0f;    // m²: Σ over its voxel sides of |Σ_f w_f·d_f| · h²
    vec3 radiance{0.0f};  // power / area
};

struct BrightPatchSettings {
    float factor = 8.0f;  // ≤ 0: no patches
    int cellVoxels = 8;
    int maxPatches = 256;
};

struct BrightPatchSplit {
    std::vector<BrightPatch> patches;
    size_t faces = 0;                        // voxel faces taken into the patches
    std::vector<FaceRadiance> restFaces;     // the voxels' face radiance less those faces
    std::vector<vec3> restRadiance;          // faceWeightedMean of restFaces
};

// Empty patches (and rest = the voxels' own radiance) when factor ≤ 0 or the voxels have no
// face radiance.
BrightPatchSplit splitBrightPatches(const VoxelScene& voxels, const BrightPatchSettings& settings);

// Adds to irradiance[k] the patches' irradiance at point k, each patch a square of its area
// centred on its position across its normal (Lambert's polygon formula: L·A·cos·cos/r² far
// from it, π·L right against it), seen from origins[k], where the point's gather starts (the
// cones' apex, or the surface its rays leave: ray_gather.h fanOrigins); a patch facing away,
// or behind a triangle of `bvh` (one shadow ray to its centre that stops one voxel short of
// it), is left out. Why the gather's own start: from the cones' apex, 1.5 voxels off the
// surface, a point by rays saw the bright patches nearer than its rays did, and the two
// rooms' first bounce came out 2.4% brighter than the path tracer's, 0.9% from the rays'
// start (build/accuracy/accuracy_bounces on a job of scenes/two_rooms.gltf, 111 voxels,
// 2026-11-27).
// TBB-parallel over the points; the same bytes at any thread count.
void addBrightPatchIrradiance(const std::vector<GatherPoint>& points, const std::vector<vec3>& origins,
                              const std::vector<BrightPatch>& patches, const BvhView& bvh, float voxelSize,
                              std::vector<vec3>& irradiance);

}  // namespace vl
