// The voxel size a bake uses when the user gives neither `resolution` nor `voxel-size`: the
// coarsest that keeps each feature of the scene within the error the accuracy issue asks of the
// bake. The features that set it, each measured by what it does to the bake as the voxels
// coarsen: how far light goes between the scene's surfaces (kVoxelsPerFreePath), the scene's
// size where no free path applies (kSceneVoxels), each point or spot light's clearance from the
// nearest surface (kMaxRefinement), and the memory available. Walls thinner than a voxel,
// emitters of any size or distance from a surface, the scene's orientation (the grid turns with
// it) and the lightmap's texel size do not set it: measured not to need voxels, or by
// construction. The measurements: docs/decisions.md, "A voxel size the scene needs".
#pragma once

#include "bake/bake_settings.h"
#include "scene/scene.h"

#include <string>
#include <vector>

namespace vl {

// The free-path rule: this many voxels along the mean free path of cosine rays from the
// scene's surfaces (surfaceFreePaths). The indirect light's detail follows the distances it
// crosses between bounces, not the scene's extent. The count along the scene's own longest side
// is rounded to fit the gather cells (cellAlignedCount in voxel_size.cpp), at most
// kMaxFreePathVoxels (a warning).
constexpr double kVoxelsPerFreePath = 31.0;  // the free-path rule
// The size rule, where no free path applies: this many voxels along the scene's longest side,
// in its own frame, for an open scene (most of its surfaces' rays leave it: zdm2, the window
// room) and for a bake told to gather by cones (gather-visibility=cones), whose error does not
// fall with finer voxels. Where auto picks cones (on the gather points, which need the voxel
// size first) the free-path rule stands.
constexpr int kSceneVoxels = 95;      // the size rule where no free path applies (8k − 1)
// The lights' rule: a point or spot light less than about half a voxel from a surface falls
// into that surface's voxel layer and loses most of the light it gives the bounces, so the
// voxels are made fine enough that every light clears one voxel. Never finer than what fits in
// the memory available (bake.h checkMemoryBudget's estimate), and never more than this many
// times finer than the rules above, so a light placed on a surface cannot make a bake of
// billions of voxels; either limit is a warning naming the light it leaves unresolved.
constexpr int kMaxRefinement = 8;     // the lights' rule goes at most this much finer
// The free-path rule's most voxels along the longest side: a scene of narrow gaps (dense
// furniture, foliage) would ask for a grid no bake of its size needs.
constexpr int kMaxFreePathVoxels = kMaxRefinement * (kSceneVoxels + 1) - 1;  // 767

// How far light goes between the scene's surfaces: `rays` cosine-distributed rays from points
// spread uniformly over its surface area (fixed seed), each from the front of its triangle.
// In a closed convex room the mean is 4V/S (Cauchy's formula for cosine chords: 2/3 of a
// cube's side). Rays that leave the scene are counted apart.
struct FreePaths {
    int rays = 0, hits = 0;
    int singleSidedBacks = 0;         // of the hits, on the back of a single-sided surface
    double mean = 0.0, median = 0.0;  // metres, over the rays that hit
};
FreePaths surfaceFreePaths(const Scene& scene, int rays = 4096);

struct LightClearance {
    std::string light;
    double metres = 0.0;  // distance from the light to the nearest triangle
};

struct VoxelSizeChoice {
    double voxelSize = 0.0;      // metres
    int voxelsAlongLongest = 0;  // the axis-aligned box's longest side in voxels (rounded)
    std::string setBy;           // what set it, in words: "the scene's size", "light 'lamp' …"
    FreePaths freePaths;                     // the probe (rays == 0 where the user set the size)
    std::vector<LightClearance> clearances;  // every point and spot light, nearest first
    std::vector<std::string> warnings;       // features the size leaves unresolved
};

// The choice for `scene` (in its local frame) under `settings`; a user's voxel-size or
// resolution is returned as set (setBy says so). Throws InputError for a scene without
// triangles or with a non-finite position (voxelSizeFor's checks), SettingsError when not even
// the size rule fits in memory.
VoxelSizeChoice chooseVoxelSize(const Scene& scene, const BakeSettings& settings);

// "voxel size 8.88 mm (63 along the longest side), set by …": the progress line.
std::string describeVoxelSize(const VoxelSizeChoice& choice);

}  // namespace vl
