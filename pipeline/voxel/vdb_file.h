// VoxelScene ⇄ one .vdb file. The grids carry the names of DESIGN.md so any VDB tool shows
// them as they are: albedo, normal, emission, opacity, occlusion, solid, radiance, plus the
// six signed-axis normal weights as axis_weights_pos (+X, +Y, +Z) and axis_weights_neg
// (−X, −Y, −Z). All of them share one linear transform of voxel size h with OpenVDB's index
// convention (voxel (i, j, k) centred at (i, j, k)·h), turned by the scene's frame and
// translated by its origin, so the grids sit where the scene sits in world space. Every channel grid is active exactly
// at VoxelScene::coords; `solid` is a marker, active only where a voxel is solid. Optional
// channels (emission, occlusion, radiance) are written only when present.
//
// File metadata: voxel_size (double), settings, source_scene, voxlight_version (strings).
//
// Free of OpenVDB types: the library links OpenVDB privately.
#pragma once

#include "voxel/voxel_scene.h"

#include <string>
#include <vector>

namespace vl {

// A grid beside the VoxelScene ones with its own voxel size, e.g. the cone stage's radiance
// mip levels (voxel size 2^k·h). Exactly one of `scalars` and `vectors` is filled, parallel
// to `coords` (sorted by (x, y, z) when read back).
struct ExtraGrid {
    std::string name;
    double voxelSize = 0.0;
    std::vector<ivec3> coords;
    std::vector<float> scalars;  // written as a FloatGrid
    std::vector<vec3> vectors;   // written as a Vec3SGrid
    glm::dvec3 translation{0.0};  // world position of voxel (0, 0, 0)'s centre
    glm::dmat3 frame{1.0};        // its axes in world space (VoxelScene::frame)

    // An empty grid (no coords) is written as a FloatGrid.
    bool isVector() const { return !vectors.empty(); }
};

// Names of the grids written for a VoxelScene.
namespace grid_names {
inline constexpr const char* albedo = "albedo";
inline constexpr const char* normal = "normal";
inline constexpr const char* emission = "emission";
inline constexpr const char* opacity = "opacity";
inline constexpr const char* occlusion = "occlusion";
inline constexpr const char* solid = "solid";
inline constexpr const char* radiance = "radiance";
inline constexpr const char* axisWeightsPos = "axis_weights_pos";
inline constexpr const char* axisWeightsNeg = "axis_weights_neg";
}  // namespace grid_names

// Writes the scene's grids and `extra` to `path` atomically. Throws Error for inconsistent
// channel sizes, a NaN/Inf value (naming the grid and voxel), an extra grid whose name
// clashes with another, or a failed write (naming the file).
void writeVoxelFile(const VoxelScene& voxels, const std::string& path, const std::vector<ExtraGrid>& extra = {});

// Reads a file written by writeVoxelFile (VoxelScene::origin and frame from the grids' transform).
// InputError naming the file (and the grid) when the file is missing or not a VDB, a
// required grid is missing or of the wrong type, a transform is not a uniform scale, a
// rotation and a translation, or the grids disagree on voxel size, transform or active voxels. Grids other than ours are ignored.
VoxelScene readVoxelFile(const std::string& path);

// Reads one float or Vec3f grid by name (e.g. an ExtraGrid written beside the scene).
ExtraGrid readExtraGrid(const std::string& path, const std::string& gridName);

}  // namespace vl
