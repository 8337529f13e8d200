// What voxelization gives every later stage: one sparse topology of active voxels and
// parallel channel arrays, free of OpenVDB types so that lighting, cone tracing and the
// CUDA launchers include it cheaply. voxel/vdb_file.h turns it into OpenVDB grids named as
// DESIGN.md says (albedo, normal, emission, opacity, occlusion, solid, radiance) and back.
//
// Index space follows OpenVDB: voxel (i, j, k) is centred at world (i, j, k)·h and spans
// [(i−½)h, (i+½)h] on each axis; the transform is a plain linear scale by h.
#pragma once

#include "core/math.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vl {

// Six signed-axis faces of a voxel, in this order: +X, −X, +Y, −Y, +Z, −Z.
using AxisWeights = std::array<float, 6>;

struct VoxelSettings {
    double voxelSize = 0.0;   // metres; 0 = derive from resolution
    int resolution = 128;     // voxels along the scene's longest axis when voxelSize is 0
    bool fillInterior = false;  // also mark voxels inside closed meshes solid
    int texelSamples = 4;     // texture samples per axis per voxel face area, over each triangle piece (albedo, emission)
};

struct VoxelScene {
    double voxelSize = 0.0;
    std::string sourceScene;  // path of the glTF it came from
    std::string settings;     // human-readable settings, stored as file metadata

    // Active voxels sorted by (x, y, z) lexicographically; every channel is parallel to it.
    std::vector<ivec3> coords;
    std::vector<vec3> albedo;        // area-weighted mean base colour (linear)
    std::vector<vec3> normal;        // area-weighted mean normal; unit, or zero where normals cancel
    std::vector<AxisWeights> axisWeights;  // area-weighted positive/negative normal parts per axis
    std::vector<vec3> emission;      // radiance; empty when the scene has no emitters
    std::vector<float> opacity;      // coverage α in (0, 1]
    std::vector<uint8_t> solid;      // 1 = blocks light completely (marker grid)
    std::vector<vec3> radiance;      // outgoing diffuse radiance, written by the lighting stage
    std::vector<float> occlusion;    // mean visibility loss V over lights, written by lighting

    size_t size() const { return coords.size(); }
    vec3 centre(size_t i) const { return vec3(coords[i]) * static_cast<float>(voxelSize); }
};

}  // namespace vl
