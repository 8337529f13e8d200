// The voxel size a bake uses when the user gives neither `resolution` nor `voxel-size`:
// chosen from what the scene holds, the coarsest that keeps each feature within the error the
// accuracy issue asks of the bake (README "A voxel size the scene needs").
//
// Features, each measured by what it does to the bake as the voxels coarsen:
//  * how far light goes between the scene's surfaces: kVoxelsPerFreePath voxels along the
//    mean free path of cosine rays from its surfaces (surfaceFreePaths). The indirect
//    light's detail follows the distances it crosses between bounces, not the scene's extent:
//    the Cycles Cornell boxes (mean free path 27.3 / 27.2 cm, 55.9 cm long) and the two rooms
//    (1.88 m, 6.1 m long) have their best error² × time at 63 and 103–127 voxels along their
//    longest sides, 31–35 along their free paths (`voxlight bench`, gather level 2,
//    2026-11-27). The count along the scene's own longest side is rounded to fit the gather
//    cells (cellAlignedCount in voxel_size.cpp), at most kMaxFreePathVoxels (a warning).
//  * the scene's size, where no free path applies: kSceneVoxels along its longest side, in
//    its own frame, for an open scene (most of its surfaces' rays leave it: zdm2, the window
//    room) and for a bake told to gather by cones (gather-visibility=cones), whose error does
//    not fall with finer voxels (zdm2 by cones: 21.8 / 36.9 / 25.2 / 19.3% image error at 95
//    / 111 / 127 / 159 voxels). Where auto picks cones (on the gather points, which need the
//    voxel size first) the free-path rule stands.
//    Until 2026-11-27 this rule alone set every scene's size, at 111 voxels and gather
//    level 3: the coarsest count that held the turned Cycles boxes within 3% while the grid
//    stayed on the world axes (scene/own_frame.h).
//  * each point or spot light's clearance, its distance to the nearest surface: a light less
//    than about half a voxel from a surface falls into that surface's voxel layer and loses
//    most of the light it gives the bounces (a point light 0.32 voxel under a ceiling: −21% of
//    the room's first bounce, 0.16 voxel: −60%; 0.64 voxel and more: within the coarse grid's
//    own +1…+7%). The voxels are made fine enough that every light clears one voxel.
//  * the memory budget: never finer than what fits in the memory available
//    (bake.h checkMemoryBudget's estimate), and never more than kMaxRefinement times finer
//    than the rules above, so a light placed on a surface cannot make a bake of billions of
//    voxels; either limit is a warning naming the light it leaves unresolved.
// Measured not to need voxels, so they do not set the size: walls thinner than a voxel (the
// dark one of two sealed rooms keeps at most 0.30% of the lit one's light, at a wall half a
// voxel thick: each side of a wall gathers and reflects on its own), emissive surfaces of
// any size or distance from a surface (their light is integrated over their triangles
// exactly: a 1 cm emitter kept its first bounce within the coarse grid's own bias down to 16
// voxels across its room) and, since the grid turns with the scene, its orientation. Nor, by
// construction, the lightmap's texel size: the direct light is exact per texel and the
// indirect light is gathered on 4-voxel cells whatever the texels (not measured against a
// finer reference: the Cycles references are 256² only).
#pragma once

#include "bake/bake_settings.h"
#include "scene/scene.h"

#include <string>
#include <vector>

namespace vl {

constexpr double kVoxelsPerFreePath = 31.0;  // the free-path rule
constexpr int kSceneVoxels = 95;      // the size rule where no free path applies (8k − 1)
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

// "4.9 cm", "1.25 m", "0.56 mm": a length as a person reads it.
std::string lengthText(double metres);

// "voxel size 8.88 mm (63 along the longest side), set by …": the progress line.
std::string describeVoxelSize(const VoxelSizeChoice& choice);

}  // namespace vl
