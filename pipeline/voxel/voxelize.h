// Scene → VoxelScene: conservative, attribute-carrying voxelization (DESIGN.md "Grids").
//
// Takes the world-space triangles of a Scene and VoxelSettings; gives the sparse active
// voxels with every channel except radiance and occlusion (the lighting stage writes those),
// each a mean over the triangle pieces inside a voxel weighted by their visible area; what
// each channel holds is at voxelize(). Conservative, so nothing leaks between adjacent
// triangles. Deterministic: triangles are processed in parallel (TBB) into (voxel, triangle)
// fragments, sorted by (voxel, triangle) and reduced in that order in double precision, so
// the output is the same bytes at any thread count.
#pragma once

#include "core/progress.h"
#include "scene/scene.h"
#include "voxel/voxel_scene.h"

#include <cstddef>

namespace vl {

// Figures of one run, for logs and benchmarks.
struct VoxelizeStats {
    size_t triangles = 0;       // triangles voxelized (zero-area ones are skipped)
    size_t fragments = 0;       // (voxel, triangle) pieces before the reduction
    size_t interiorVoxels = 0;  // voxels added by fillInterior
    double surfaceArea = 0.0;   // Σ over voxels of the visible piece areas, m²
    double channelBytes = 0.0;  // bytes of coords + channels in the VoxelScene
    double denseBytes = 0.0;    // the same channels as dense arrays over the active bounding box
};

// The voxel size a run would use (settings.voxelSize, or the scene's longest extent /
// settings.resolution). Throws SettingsError for a resolution ≤ 0, a voxel size that is
// negative, NaN or infinite, texelSamples outside [1, 64], or a voxel count that would be
// absurd (more than 2^21 voxels along an axis, or an estimated 2^31 (voxel, triangle)
// pieces); InputError for a scene without triangles or with a non-finite position.
double voxelSizeFor(const Scene& scene, const VoxelSettings& settings);

// Moves the scene's local frame (Scene::moveOrigin) so its bounding box's centre sits on the
// corner shared by voxels −1 and 0 on every axis. A bake turns the scene into its own frame
// first (scene/own_frame.h, VoxelSettings::ownFrame), so the grid runs along its walls. Why: that corner is a cell corner at every
// level of the voxel hierarchy (level k groups voxels 2^k·I … 2^k·I + 2^k − 1), so the box's
// 90° rotations and mirror images map voxels, mips and gather cells onto themselves, and the
// grid follows the scene, not the world origin. A bake (bake.h) anchors the scene it is
// given; anything that voxelizes a scene to pair it with another bake's grids must too.
void anchorToVoxelGrid(Scene& scene, double voxelSize);

// The voxels and their channels (emission only when the scene has emitters):
// - A voxel is active when a triangle overlaps its closed box by the separating axis test
//   and leaves a piece of positive area inside (triangle_box.h: a voxel only touched along
//   its boundary gets no piece and is not active; the active closed boxes still cover the
//   whole surface, so nothing leaks between adjacent triangles).
// - Per piece the visible area is the clipped area × the material's visibility: 1 for
//   opaque, the fraction of texture samples at or above alphaCutoff for MASK, the mean
//   alpha for BLEND, times (1 − transmission). Every channel is a mean over the pieces
//   weighted by that visible area.
// - albedo: base colour (factor × texture × COLOR_0) sampled on texelSamples² points per
//   voxel face area (h²) spread over each piece by area (at least one per fan triangle of
//   the piece), not at its vertices; emission likewise (emissionAt). The
//   points are the centroids of a regular subdivision (exact for colours linear over the
//   piece); texture detail finer than their spacing is point-sampled and can alias, as
//   Texture has no mip levels to prefilter with. Materials without textures or varying
//   COLOR_0 are not sampled at all: their colour is exact.
// - normal: the mean geometric normal (winding), unit, or zero where the normals cancel.
// - axisWeights: Σ area·max(±n_a, 0) per signed axis, in voxel-face units (area / h²).
//   A doubleSided material is a surface on both sides, so its pieces add their area to
//   both the +a and −a faces (area·|n_a| each); the normal channel keeps the geometric
//   normal. A thin wall modelled as two single-sided faces gets both faces from geometry.
// - opacity α = min(1, Σ visible area / h²): a flat surface crossing the voxel parallel to
//   a face has α = 1; a surface that leaves part of the voxel's cross-section open less.
// - solid = 1 when α ≥ 1; with fillInterior also every voxel whose centre lies inside a
//   closed mesh (winding number of a ray along +z through the voxel column): interior
//   voxels the surface does not reach become active with α = 1, the albedo of the mesh
//   material's baseColorFactor, zero normal, zero axis weights and zero emission.
// `progress`, when given, is advanced by one per triangle (construct it with
// scene.triangleCount()).
VoxelScene voxelize(const Scene& scene, const VoxelSettings& settings, Progress* progress = nullptr,
                    VoxelizeStats* stats = nullptr);

}  // namespace vl
