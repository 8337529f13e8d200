// Voxel direct light by shadow rays against the triangles: takes the voxels, the points on the
// surface inside each voxel side (surface_points.h) and the traced scene; gives
// VoxelScene::faceRadiance, per face the light its side reflects, albedo/π × the area-mean of
// the direct irradiance over the side's points (lighting/direct_light.h surfacePointIrradiance:
// lights, a sun's disk, emitters; and the sky, skyIrradiance, by skyStrata² rays a point),
// VoxelScene::radiance their faceWeightedMean and VoxelScene::occlusion the share of the
// points' shadow rays that were blocked.
//
// Why, beside the stepping pass of lighting.h (ERRATA eq. 17): a visibility walk through the
// voxels sees thin occluders (window frames, mullions) as partly open voxels, weighted down by
// their distance, and evaluates a voxel at one point, so a sun through a window brings too
// much light (docs/accuracy.md, "Where the light was wrong, and why").
#pragma once

#include "lighting/surface_points.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"
#include "voxel/voxel_scene.h"

namespace vl {

class Progress;

struct SurfaceLightStats {
    size_t points = 0;       // surface points shaded
    size_t emptySides = 0;   // voxel sides no point fell in: they take their voxel's other sides' light
    double seconds = 0.0;
};

// Fills voxels.faceRadiance, radiance and occlusion. A side no point fell in (a sliver of a
// triangle whose points all fell in neighbouring voxels) takes the area-mean irradiance of the
// voxel's sides that face its way, else none. The same bytes at any thread count. `progress`
// advances by one per voxel.
// skyStrata 0: no sky.
SurfaceLightStats lightVoxelsByRays(VoxelScene& voxels, const VoxelSurfacePoints& points, const TraceSceneView& scene,
                                    const BvhView& bvh, int skyStrata, Progress* progress = nullptr);

// The part of lightVoxelsByRays's faceRadiance that the punctual lights give (no emitters, no
// sky): what a gather ray that hits can take exactly at its hit point instead (bake setting
// hit-light exact). Empty when the scene has no punctual light.
std::vector<FaceRadiance> punctualFaceRadiance(const VoxelScene& voxels, const VoxelSurfacePoints& points,
                                               const TraceSceneView& scene, const BvhView& bvh);

}  // namespace vl
