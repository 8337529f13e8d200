// Bright patches: the final gather's split of the voxels' light into the bright surfaces
// (sunlit floor, a lamp's hot spot) and the diffuse rest. Takes the lit voxels (after the
// bounces) and the points on their surfaces (lighting/surface_points.h); gives the patches and
// the rest's face radiance. The rest is what the gather's rays read; the patches' light is added
// at each gather point by sampling points of their surfaces with shadow rays.
//
// Why: a few percent of a sunlit room's surface sends most of its first bounce. Cosine rays find
// such a patch by chance, so neighbouring gather points differ by their luck and the ceiling
// looks mottled. Sampling the patches' own surface points, chosen by what each patch can send
// the gather point, takes the luck out (docs/decisions.md, "Bright patches").
#pragma once

#include "gather/irradiance_cache.h"
#include "lighting/surface_points.h"
#include "trace/bvh.h"
#include "voxel/voxel_scene.h"

#include <vector>

namespace vl {

struct BrightPoint {
    vec3 position{0.0f};         // on its triangle, local frame
    vec3 geometricNormal{0.0f};  // unit, the side it sends light from
    vec3 normal{0.0f};           // unit shading normal on that side
    vec3 radiance{0.0f};         // its voxel side's face radiance
    float area = 0.0f;           // m² it stands for
};

struct BrightPatch {
    vec3 position{0.0f};  // the area-weighted centre of its points
    vec3 normal{0.0f};    // unit: the area-weighted normal of its points (zero where they cancel)
    float area = 0.0f;    // m²
    float radius = 0.0f;  // the largest distance of a point from the centre
    vec3 radiance{0.0f};  // the area-mean of its points' radiance (grey: what the draws weigh by)
    uint32_t firstPoint = 0, pointCount = 0;  // BrightPatchSplit::points
};

struct BrightPatchSettings {
    float factor = 8.0f;  // ≤ 0: no patches
    int cellVoxels = 8;
    int maxPatches = 256;
    int samples = 64;     // shadow-ray samples of the patches per gather point
};

struct BrightPatchSplit {
    std::vector<BrightPatch> patches;
    std::vector<BrightPoint> points;         // the patches' points, patch by patch
    std::vector<float> pointCdf;             // per point, inclusive, by area × radiance within its patch
    size_t faces = 0;                        // voxel faces taken into the patches
    std::vector<FaceRadiance> restFaces;     // the voxels' face radiance less those faces
    std::vector<vec3> restRadiance;          // faceWeightedMean of restFaces
    // hit-light exact (no patches then): the punctual lights' part of restFaces, which the
    // lightmap records' rays take at their hit points instead (gather/ray_gather.h FanExtras).
    std::vector<FaceRadiance> lightsAtHits;
};

// A face is bright when its radiance exceeds `factor` times the area-weighted mean of all faces.
// A voxel side with a bright face is bright whole: its faces leave the rest, and its surface
// points (each with its side's face radiance) join the patch of its cell of `cellVoxels`³ voxels
// and the signed axis its normal is closest to. The `maxPatches` most powerful patches are
// split off; the others stay in the rest. Empty patches (and rest = the voxels' own light) when
// factor ≤ 0 or the voxels have no face radiance. `points`: voxelSurfacePoints of the same
// voxels.
BrightPatchSplit splitBrightPatches(const VoxelScene& voxels, const VoxelSurfacePoints& points,
                                    const BrightPatchSettings& settings);

// The patches' irradiance at a surface point (origin, on the surface, unit normal n) from
// `samples` points drawn among them: a patch with probability by what its area could send
// (its power, the cosines at its centre and the distance, never zero where a point of it may
// lie above n's horizon), a point within it by area × radiance. Each drawn point y counts as a
// small disk of its area a facing its normal, L·cos·cos·a / (d² + a/π) (bounded where d → 0),
// behind a shadow ray from origin to y. `seed` stratifies the draws. Unbiased over the disks
// but for that bound.
// `variance`, when given, receives the estimate's variance (mean channel) from the spread of
// its samples.
vec3 brightPatchIrradiance(const BrightPatchSplit& split, const BvhView& bvh, const vec3& origin, const vec3& n,
                           int samples, uint64_t seed, float* variance = nullptr);

// Adds brightPatchIrradiance at every gather point to irradiance[k], seen from origins[k]
// (where its gather starts: the surface its rays leave, or the cones' apex). TBB-parallel over
// the points; the same bytes at any thread count. Error when the counts differ.
void addBrightPatchIrradiance(const std::vector<GatherPoint>& points, const std::vector<vec3>& origins,
                              const BrightPatchSplit& split, const BvhView& bvh, int samples,
                              std::vector<vec3>& irradiance);

}  // namespace vl
