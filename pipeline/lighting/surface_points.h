// Points on the surface inside each voxel side: takes the scene's triangles as the tracer holds
// them (global triangle ids) and the voxels; gives, per voxel side (voxel_scene.h voxelSides
// order), points spread over the triangles' area inside that voxel, each with the area it
// stands for. A double-sided triangle gives each point to both its sides.
//
// Why: a voxel averages the surface inside it, but light arrives at the surface: a voxel side's
// direct light is the area-mean of the exact irradiance over these points (surface_light.h),
// and the final gather samples the bright sides' light at them (gather/bright_patches.h), with
// shadow rays against the triangles that end on the surface itself.
#pragma once

#include "trace/trace_scene.h"
#include "voxel/voxel_scene.h"

#include <cstdint>
#include <vector>

namespace vl {

struct SurfacePoint {
    vec3 position{0.0f};  // on its triangle, the voxels' local frame
    vec3 normal{0.0f};    // unit shading normal on the side's side of the triangle
    vec3 geometricNormal{0.0f};  // unit, on the same side
    // Unit, across the normal, along its triangle's first edge: a frame that turns with the
    // scene, so what is sampled about the point does not change with the scene's placement.
    vec3 tangent{0.0f};
    uint32_t triangle = ~0u;     // global triangle id (TraceSceneView)
    float area = 0.0f;           // m² it stands for
    // Its triangle, its place among the triangle's points and its side: a seed and an order
    // that the scene's placement does not change.
    uint64_t id = 0;
};

struct VoxelSurfacePoints {
    // Points of side s of voxel v (slot 6·v + s): points[begin[slot] … begin[slot + 1]).
    std::vector<uint32_t> begin{0};
    std::vector<SurfacePoint> points;
    size_t slotCount() const { return begin.size() - 1; }
};

// About `perVoxelFace` points per h² of each triangle's area, at least one a triangle, laid out
// by a low-discrepancy sequence over the triangle (each triangle its own offset), each assigned
// to the voxel holding it and the side of that voxel whose normal is nearest its own. The same
// points for any thread count. Error when perVoxelFace is not in 1 … 256.
VoxelSurfacePoints voxelSurfacePoints(const VoxelScene& voxels, const TraceSceneView& scene, int perVoxelFace);

}  // namespace vl
