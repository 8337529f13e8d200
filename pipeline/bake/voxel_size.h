// The voxel size a bake uses when the user gives neither `resolution` nor `voxel-size`:
// chosen from what the scene holds, the coarsest that keeps each feature within the error the
// accuracy issue asks of the bake (README "A voxel size the scene needs").
//
// Features, each measured by what it does to the bake as the voxels coarsen:
//  * the scene's size: kSceneVoxels voxels along its longest side, measured in its own frame
//    (the axes of its most common surface orientations) so a scene modelled at an angle to
//    the world axes gets the voxels it would get unturned. 111: the coarsest count at which
//    the Cycles quad box's lightmap meets issue 13's 3% against Cycles at each of sixteen
//    turns (2.41–2.84%; 103 voxels: 3.13%, 95: 3.26%; build/accuracy/accuracy_rotations,
//    2026-11-27). By error² × time alone 63–95 voxels are cheaper on both Cornell boxes (111
//    is 1.18 / 1.17× the best lightmap point, `voxlight bench`, 2026-11-27), and 127 on the
//    two rooms (111: 1.19×), whose error is not a smooth function of the voxel size
//    (2.63–3.41% over 101–133 voxels). 63 was the rule while the gathers went by cones, whose
//    error did not fall with finer voxels (quad 4.9% at 63, 5.9% at 111). Tried and not
//    taken: 6 voxels along the median free path between surfaces (103 on zdm2: 28.0% image
//    error against 31.3% at 63, by cones, but 1.2× the error² × time).
//  * each point or spot light's clearance, its distance to the nearest surface: a light less
//    than about half a voxel from a surface falls into that surface's voxel layer and loses
//    most of the light it gives the bounces (a point light 0.32 voxel under a ceiling: −21% of
//    the room's first bounce, 0.16 voxel: −60%; 0.64 voxel and more: within the coarse grid's
//    own +1…+7%). The voxels are made fine enough that every light clears one voxel.
//  * the memory budget: never finer than what fits in the memory available
//    (bake.h checkMemoryBudget's estimate), and never more than kMaxRefinement times finer
//    than the size rule, so a light placed on a surface cannot make a bake of billions of
//    voxels; either limit is a warning naming the light it leaves unresolved.
// Measured not to need voxels, so they do not set the size: walls thinner than a voxel (the
// dark one of two sealed rooms keeps at most 0.30% of the lit one's light, at a wall half a
// voxel thick: each side of a wall gathers and reflects on its own) and emissive surfaces of
// any size or distance from a surface (their light is integrated over their triangles
// exactly: a 1 cm emitter kept its first bounce within the coarse grid's own bias down to 16
// voxels across its room). Nor, by construction, the lightmap's texel size: the direct light
// is exact per texel and the indirect light is gathered on 8-voxel cells whatever the texels
// (not measured against a finer reference: the Cycles references are 256² only).
#pragma once

#include "bake/bake_settings.h"
#include "scene/scene.h"

#include <string>
#include <vector>

namespace vl {

constexpr double kVoxelsPerFreePath = 31.0;  // the free-path rule
constexpr int kSceneVoxels = 95;      // the size rule where no free path applies: an odd count
constexpr int kMaxRefinement = 8;     // the lights' rule goes at most this much finer

// How far light goes between the scene's surfaces: `rays` cosine-distributed rays from points
// spread uniformly over its surface area (fixed seed), each from the front of its triangle.
// In a closed convex room the mean is 4V/S (Cauchy's formula for cosine chords: 2/3 of a
// cube's side). Rays that leave the scene are counted apart.
struct FreePaths {
    int rays = 0, hits = 0;
    int singleSidedBacks = 0;         // of the hits, on the back of a single-sided surface
    double mean = 0.0, median = 0.0;  // metres, over the rays that hit
    double backShare() const { return hits > 0 ? double(singleSidedBacks) / hits : 0.0; }
};
FreePaths surfaceFreePaths(const Scene& scene, int rays = 4096);

struct LightClearance {
    std::string light;
    double metres = 0.0;  // distance from the light to the nearest triangle
};

struct VoxelSizeChoice {
    double voxelSize = 0.0;      // metres
    int voxelsAlongLongest = 0;  // the scene's longest side in voxels (odd)
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
