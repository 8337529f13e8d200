// The gather by rays: takes gather points (cone/irradiance_cache.h), the radiance mips, the
// BVH and the traced scene; gives the irradiance at each point from n × n rays against the
// scene's triangles, each reading the mips where it hits, filtered over the footprint that a
// cone of the ray's share of the hemisphere has there. Cones find what they see by
// compositing the mips' opacity; rays find it exactly and keep the mips' prefiltered radiance.
//
// Why: a cone reads a coarse mip voxel as partly opaque wherever a wall lies within its
// trilinear footprint, a whole voxel of that level to every side, so walls seen edge-on are a
// fog, a block beside a cone's path dims it, and the coarse samples at a cone's far end reach
// through a wall into the room behind it (README, "Where the Cornell boxes' indirect error
// comes from"). Against the path tracer on zdm2, eight bounces of cones hold 1.25 times the
// light of nine-bounce paths, eight bounces of rays 1.00 (/work notes: the bounce series
// compared bounce by bounce). On the Cycles Cornell boxes the lightmaps' error falls from
// 4.95% / 5.82% to about 4% / 3.8% at the same voxel size and time (README, accuracy).
//
// A ray leaves the point's surface: from the point lifted off its surface (liftOffSurface), a
// ray back along −n finds the surface within three voxels, and the rays start on it (offset
// by offsetRayOrigin); where none is found they start at the lifted point. The n × n
// directions are cosine-distributed and stratified, turned about the normal by the point's
// frame (gatherFrame), so a point's rays turn with the scene. A ray that hits at distance t
// reads the level whose voxel matches D = max(h, 2·t·tan ψ)/2 (as cones do, one level finer
// than the footprint: cone_trace.h), ψ the half-angle of a cone of the ray's solid angle
// π/(N·cos θ), at half a voxel of that level in front of the hit, each voxel seen from the
// ray's origin (sampleMipLevel). A ray that leaves the scene reads nothing.
//
// The mips show a surface's front, and a double-sided surface's back; the back of a
// single-sided one shows nothing. A path tracer (and Cycles) reflects light off both sides of
// every surface, so in a scene whose rays see many such backs (zdm2: 38% of the final
// gather's hits) rays lose light at every bounce where the blur of cones keeps some:
// probeSingleSidedBacks measures it, and the bake gathers by cones there (bake_settings.h
// gatherVisibility).
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
