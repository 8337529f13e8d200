// The gather by rays: takes gather points (cone/irradiance_cache.h), the radiance mips, the
// BVH and the traced scene; gives the irradiance at each point from n × n rays against the
// scene's triangles, each reading the light of the voxels where it hits. Cones find what they
// see by compositing the mips' opacity; rays find it exactly, and the voxels still hold the
// light (direct light and every earlier bounce).
//
// Why: a cone reads a coarse mip voxel as partly opaque wherever a wall lies within its
// trilinear footprint, a whole voxel of that level to every side, so walls seen edge-on are a
// fog, a block beside a cone's path dims it, and the coarse samples at a cone's far end reach
// through a wall into the room behind it (README, "Where the Cornell boxes' indirect error
// comes from"). A ray finds the surface it sees exactly and reads only the voxels that surface
// passes through. On the Cycles Cornell boxes at 111 voxels the lightmaps' error against
// Cycles is 2.95% / 2.99% by rays and 5.9% / 5.8% by cones (quad / point), and the bright
// sealed rooms of scenes/two_rooms.gltf leak 0.04% / 0% / 0% through walls 0.5 / 1 / 2 voxels
// thick by rays, 0.10% / 0.18% / 0.41% by cones (`voxlight bench`, README "Rays for
// visibility").
//
// A ray leaves the point's surface: from the point lifted off its surface (liftOffSurface), a
// ray back along −n finds the surface within three voxels, and the rays start on it (offset
// by offsetRayOrigin); where none is found they start at the lifted point. The n × n
// directions are cosine-distributed and stratified, turned about the normal by the point's
// frame (gatherFrame), so a point's rays turn with the scene. Where a ray hits a surface of
// normal n it reads, along each axis a (weight n_a²), the level-0 texel that shows the face
// looking back at it (radiance_mips.h) in the voxel holding the hit or its neighbour along a,
// whichever shows more surface. Only voxels the surface passes through are read: reading the
// level that matches a cone of the ray's solid angle instead (trilinear around the hit) let
// the far rays of the bright rooms read the lit room's floor across the wall (room B 0.29% /
// 0.41% / 0.25% of room A at walls 0.5 / 1 / 2 voxels) for the same Cornell error. A ray that
// leaves the scene reads nothing.
//
// The mips show a surface's front, and a double-sided surface's back; the back of a
// single-sided one shows nothing. A path tracer (and Cycles) reflects light off both sides of
// every surface, so in a scene whose rays see many such backs (zdm2: 38.5% of the probe's
// hits) rays lose light at every bounce where the blur of cones keeps some (zdm2's image by
// rays 42.0% against 24.6% by cones, `voxlight bench tools/bench/zdm2.json`):
// probeSingleSidedBacks measures it, and the bake gathers by cones there
// (gather_visibility.h).
#pragma once

#include "bake/gather_visibility.h"
#include "cone/irradiance_cache.h"
#include "cone/radiance_mips.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"

#include <string>
#include <vector>

namespace vl {

class Progress;

// E at every point (W/m²) from raysPerAxis² rays (1 … kMaxGatherRaysPerAxis, else
// SettingsError). TBB-parallel over points; the same bytes at any thread count. `progress`
// advances once per point.
std::vector<vec3> gatherByRays(const std::vector<GatherPoint>& points, const MipView& mips, const BvhView& bvh,
                               const TraceSceneView& scene, int raysPerAxis, Progress* progress = nullptr);

struct BackProbe {
    uint64_t hits = 0;              // rays that hit a triangle
    uint64_t singleSidedBacks = 0;  // of them, on the back of a single-sided material
    double share() const { return hits > 0 ? double(singleSidedBacks) / double(hits) : 0.0; }
};

// What share of the rays from `points` (raysPerAxis² each, as gatherByRays sends them) hit
// the back of a single-sided surface, the part of a scene the voxels do not show.
BackProbe probeSingleSidedBacks(const std::vector<GatherPoint>& points, float voxelSize, const BvhView& bvh,
                                const TraceSceneView& scene, int raysPerAxis);

struct GatherVisibilityChoice {
    GatherVisibility visibility = GatherVisibility::Cones;
    std::string setBy;  // why: the setting, or the probe's share against the limit
    BackProbe probe;    // hits == 0 when no probe ran
};

// `requested` when it is cones or rays; for auto, the probe from the gather points of
// `voxels` at `gatherLevel`.
GatherVisibilityChoice chooseGatherVisibility(GatherVisibility requested, const VoxelScene& voxels, int gatherLevel,
                                              const BvhView& bvh, const TraceSceneView& scene);
// One line for the progress output: "gather visibility: rays (…)".
std::string describeGatherVisibility(const GatherVisibilityChoice& choice);

}  // namespace vl
