// What voxelization gives every later stage: one sparse topology of active voxels and
// parallel channel arrays, free of OpenVDB types so that lighting, cone tracing and the
// CUDA launchers include it cheaply. voxel/vdb_file.h turns it into OpenVDB grids named as
// DESIGN.md says (albedo, normal, emission, opacity, occlusion, solid, radiance) and back.
//
// Index space follows OpenVDB: voxel (i, j, k) is centred at (i, j, k)·h in the scene's local
// frame (scene.h) and spans [(i−½)h, (i+½)h] on each axis; in world space at origin +
// frame·(i, j, k)·h (the .vdb transform: a scale by h, the frame's rotation, then a
// translation by origin).
#pragma once

#include "core/hostdev.h"
#include "core/math.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vl {

// Six signed-axis faces of a voxel, in this order: +X, −X, +Y, −Y, +Z, −Z.
using AxisWeights = std::array<float, 6>;
// One radiance per signed-axis face (same order): the light leaving the surface side that
// faces that way.
using FaceRadiance = std::array<vec3, 6>;

struct VoxelSettings {
    double voxelSize = 0.0;   // metres; 0 = derive from resolution
    int resolution = 128;     // voxels along the scene's longest axis when voxelSize is 0 (an even count less one)
    bool fillInterior = false;  // also mark voxels inside closed meshes solid
    bool ownFrame = true;       // the grid along the scene's own axes (scene/own_frame.h), not the world's
    int texelSamples = 4;     // texture samples per axis per voxel face area, over each triangle piece (albedo, emission)
};

struct VoxelScene {
    double voxelSize = 0.0;
    glm::dvec3 origin{0.0};   // world position of the local frame's origin (Scene::origin)
    glm::dmat3 frame{1.0};    // the local frame's axes in world space (Scene::frame)
    std::string sourceScene;  // path of the glTF it came from
    std::string settings;     // human-readable settings, stored as file metadata

    // Active voxels sorted by (x, y, z) lexicographically; every channel is parallel to it.
    std::vector<ivec3> coords;
    std::vector<vec3> albedo;        // area-weighted mean base colour (linear)
    std::vector<vec3> normal;        // area-weighted mean normal; unit, or zero where normals cancel
    std::vector<AxisWeights> axisWeights;  // area-weighted positive/negative normal parts per axis
    std::vector<vec3> emission;      // radiance; empty when the scene has no emitters
    // Index space: where the surface inside the voxel lies relative to its centre (the
    // coverage-weighted centroid of its pieces, each component in [−½, ½]); the lighting
    // stage evaluates a voxel's light there. Empty (voxels read from a .vdb, synthetic
    // scenes): the centres. Interior voxels (fillInterior) have 0.
    std::vector<vec3> surfaceOffset;
    std::vector<float> opacity;      // coverage α in (0, 1]
    std::vector<uint8_t> solid;      // 1 = blocks light completely (marker grid)
    std::vector<vec3> radiance;      // outgoing diffuse radiance, written by the lighting stage
    // Per face (FaceRadiance), written by lighting and bounces beside `radiance`, which is
    // their mean Σ w_f·L_f / Σ_axes max(w_+a, w_−a) (what grids.vdb stores); empty before
    // lighting and after reading a .vdb (then consumers fall back to `radiance`). A face with
    // axis weight 0 has no surface and radiance 0. See voxelSides() for which faces share a
    // surface side.
    std::vector<FaceRadiance> faceRadiance;
    std::vector<float> occlusion;    // mean visibility loss V over lights, written by lighting

    size_t size() const { return coords.size(); }
    vec3 centre(size_t i) const { return vec3(coords[i]) * static_cast<float>(voxelSize); }
};

// The surface sides of a voxel: faces that show the same surface side share one normal and
// are lit and gather light together. With mean normal n (unit, or zero where normals
// cancel), a face f with axis weight > 0 and direction d_f belongs to
//   the front side (normal n) when d_f·n > 0,
//   the back side (normal −n: the other side of a double-sided surface) when d_f·n < 0,
//   a side of its own with normal d_f when n ≈ 0 or d_f·n = 0 (no surface side to join).
// Faces with weight 0 (or a non-finite one) have no surface and belong to no side.
struct VoxelSides {
    int count = 0;
    vec3 normal[6] = {};                  // unit, sides in order of their first face
    int sideOfFace[6] = {-1, -1, -1, -1, -1, -1};
};

// The unit direction of face f (+X, −X, +Y, −Y, +Z, −Z).
VL_HOSTDEV inline vec3 faceDirection(int f) {
    vec3 d(0.0f);
    d[f >> 1] = (f & 1) ? -1.0f : 1.0f;
    return d;
}

VL_HOSTDEV inline VoxelSides voxelSides(const vec3& n, const float* axisWeights) {
    VoxelSides sides;
    const float length = glm::length(n);
    const bool cancelled = !(length >= 0.5f);  // unit or zero by contract; NaN counts as zero
    int front = -1, back = -1;
    for (int f = 0; f < 6; ++f) {
        if (!(axisWeights[f] > 0.0f) || !isFinite(axisWeights[f])) continue;
        const vec3 d = faceDirection(f);
        const float facing = cancelled ? 0.0f : d[f >> 1] * n[f >> 1];
        int* shared = facing > 0.0f ? &front : (facing < 0.0f ? &back : nullptr);
        if (shared && *shared >= 0) {
            sides.sideOfFace[f] = *shared;
            continue;
        }
        const int s = sides.count++;
        sides.normal[s] = shared ? (facing > 0.0f ? n / length : -n / length) : d;
        sides.sideOfFace[f] = s;
        if (shared) *shared = s;
    }
    return sides;
}

// Σ_f w_f·values_f / Σ_axes max(w_+a, w_−a): the isotropic mean of per-face values. The
// larger face of each ± pair, not the sum, so that a double-sided surface (equal ± weights)
// shows its lit side's radiance rather than half of it; 0 without weights.
VL_HOSTDEV inline vec3 faceWeightedMean(const vec3* values, const float* axisWeights) {
    vec3 sum(0.0f);
    float total = 0.0f;
    for (int f = 0; f < 6; ++f) {
        const float w = axisWeights[f] > 0.0f && isFinite(axisWeights[f]) ? axisWeights[f] : 0.0f;
        if (w > 0.0f) sum += w * values[f];
        if (!(f & 1)) {
            const float other = axisWeights[f + 1] > 0.0f && isFinite(axisWeights[f + 1]) ? axisWeights[f + 1] : 0.0f;
            total += glm::max(w, other);
        }
    }
    return total > 0.0f ? sum / total : vec3(0.0f);
}

}  // namespace vl
