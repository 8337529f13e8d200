// Voxel direct lighting (paper §3.3): takes a VoxelScene (albedo, normal, axis weights,
// opacity, solid) and the Scene's punctual lights and emissive triangles; gives
// VoxelScene::faceRadiance, per voxel face the diffuse light the surface side facing that
// way reflects, albedo/π × Σ_lights E·weight·(1 − V) with one visibility ray per light and
// lit side (voxel_scene.h voxelSides: the front of a surface, the back of a double-sided
// one, each face on its own where normals cancel); VoxelScene::radiance = the faces' mean
// (faceWeightedMean); and VoxelScene::occlusion = the mean visibility loss V over the lights
// that reach the voxel. Emission stays in its own channel (the bake counts it once).
//
// Visibility follows ERRATA eq. (17); the kernels are in lighting/lighting_kernels.h, written
// once for the TBB pass here and a later CUDA launcher.
#pragma once

#include "scene/scene.h"
#include "voxel/voxel_scene.h"

#include <cstdint>
#include <map>
#include <optional>
#include <string>

namespace vl {

class Progress;

// How a surface side of a voxel (normal N_s, its faces F_s) weighs incoming light
// (DESIGN.md "Normal-weighted attenuation"; lighting_kernels.h sideWeight). Where normals
// cancel each face is a side with N_s = its direction, and all three are max(N_s·L, 0).
enum class NormalWeighting {
    Lambert,   // max(N_s·L, 0): exact for a flat surface of any orientation
    Villegas,  // W = N_s∘N_s, D_a = max(sign(N_s,a)·L_a, 0), cos = Σ_a W_a·D_a
    SixAxis,   // Σ_{f∈F_s} w_f·max(dir_f·L, 0) / Σ_{f∈F_s} w_f: the side's own axis faces
};

// How visibility rays walk the grid. Both visit the same voxels in the same order and give
// bit-identical results; HDDA leaps over empty NanoVDB nodes instead of stepping through them.
enum class VisibilityTraversal { Hdda, Dda };

// The paper's eq. (18): E = I·C / (K_c + K_l·r + K_q·r²), r in metres.
struct AttenuationCoefficients {
    float constant = 0.0f;
    float linear = 0.0f;
    float quadratic = 1.0f;
};

// How the voxel pass finds what blocks a light.
enum class VoxelVisibility {
    Rays,      // shadow rays against the triangles from points on each voxel side's surface (surface_light.h)
    Stepping,  // ERRATA eq. 17: a walk through the voxels' opacity toward the light (the paper's)
};

struct LightingSettings {
    // Rays by default: a walk through the voxels sees thin occluders (window frames, mullions)
    // as partly open and weighs them down with distance, so a sun through a window brings
    // too much light (docs/accuracy.md, "Where the light was wrong, and why").
    VoxelVisibility visibilityBy = VoxelVisibility::Rays;
    // By rays: about this many surface points per h² of each triangle's area (surface_points.h).
    int surfacePoints = 4;
    // Lambert by default: it is exact on a flat surface of any orientation. Six-axis keeps a
    // 90° corner's total but lights a tilted wall by 1/‖n‖₁ of its cosine, so a turned room
    // loses indirect power (docs/decisions.md, "Normal weighting").
    NormalWeighting normalWeights = NormalWeighting::Lambert;
    VisibilityTraversal traversal = VisibilityTraversal::Hdda;
    // Punctual-light falloff. Unset: glTF physical inverse square with the KHR_lights_punctual
    // range window (spot lights add the extension's smooth cone falloff). Set: eq. (18) for
    // every point and spot light. A light named in `lightAttenuation` uses its own K's.
    std::optional<AttenuationCoefficients> attenuation;
    std::map<std::string, AttenuationCoefficients> lightAttenuation;
    // Each emissive patch (a quad's two halves, or a triangle: lighting_kernels.h) is seen
    // through n×n stratified points of its own per voxel; its unshadowed light is exact
    // (Lambert's polygon formula), so the points only shape penumbrae, and what they miss is
    // noise from voxel to voxel that the bounces' gathers average. One suffices by default:
    // more barely lowers the error and multiplies the voxel light stage's time
    // (docs/decisions.md, "Emitter strata").
    int emitterStrata = 1;
    // false: V = 0 everywhere (unshadowed lighting; the benchmark's "no stepping" peer).
    bool visibility = true;
    // Worker threads; 0 = TBB's default. Results do not depend on it.
    int threads = 0;
};

struct LightingStats {
    uint64_t voxels = 0;
    uint64_t lights = 0;            // punctual lights
    uint64_t emitterTriangles = 0;  // emissive triangles with non-zero area
    uint64_t emitterSamples = 0;     // fixed points on textured emitters (uniform ones: each voxel its own)
    uint64_t voxelLightEvaluations = 0;  // (voxel, light or emitter sample) pairs shaded
    uint64_t visibilitySteps = 0;        // voxels looked up plus empty nodes leapt over
    double seconds = 0.0;
};

const char* toString(NormalWeighting mode);
// "lambert", "villegas", "six-axis"; SettingsError for anything else.
NormalWeighting parseNormalWeighting(const std::string& name);

// Fills voxels.faceRadiance, voxels.radiance and voxels.occlusion (overwriting them). Throws SettingsError for
// settings out of range (naming the setting, or the light named in lightAttenuation that the
// scene lacks), InputError for lights or channels that would give NaN (naming the light or
// the channel). `progress`, when given, advances by one per voxel.
LightingStats lightVoxels(const Scene& scene, VoxelScene& voxels, const LightingSettings& settings,
                          Progress* progress = nullptr);

// [added by cuda] The same, with `runner` in place of the TBB loop: it runs
// lighting::shadeVoxel for voxels [0, voxelCount) into results (cuda/launchers.h passes the
// GPU launcher, so validation, preparation and the kernel stay one implementation).
namespace lighting {
struct LightingView;
struct VoxelLighting;
struct KernelStats;
}  // namespace lighting
using VoxelKernelRunner = void (*)(const lighting::LightingView& view, uint32_t voxelCount, bool hierarchical,
                                   lighting::VoxelLighting* results, lighting::KernelStats& stats);
LightingStats lightVoxels(const Scene& scene, VoxelScene& voxels, const LightingSettings& settings,
                          Progress* progress, VoxelKernelRunner runner);

}  // namespace vl
