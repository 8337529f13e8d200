// Lightmap chart seams: where one surface in 3D is two edges in the atlas, each side reads
// its own texels, and a viewer shows a line where the two disagree. Takes an atlas's meshes
// and its lightmaps; finds the seams (findLightmapSeams), measures the jump across them
// (measureSeamJump, bake.json's figures) and stitches them by a least-squares solve that
// moves the texels the seams' reads touch (stitchLightmapSeams), as production lightmappers
// do (Castaño, "Lightmap seams", The Witness). Measurements: docs/seams.md.
#pragma once

#include "core/image.h"
#include "scene/scene.h"
#include "unwrap/lightmap_uvs.h"

#include <cstdint>
#include <vector>

namespace vl {

constexpr float kSeamNormalDegrees = kSmoothShadingDegrees;  // unwrap/lightmap_uvs.h: one rule for smooth
constexpr float kSeamInsetTexels = 0.5f;
// λ against the pairs' weight 1: the smaller, the closer the seams come to one value, each
// step costing more iterations (docs/seams.md); padding moves 25 times more freely than
// covered texels.
constexpr double kStitchCoveredWeight = 0.01;
constexpr double kStitchPaddingWeight = 0.0004;

// One side of a seam, in texel coordinates (uv1 × (width, height)): the edge from `a` to `b`,
// both in the order of the 3D edge's ends, and the unit direction into its triangle.
struct SeamSide {
    vec2 a{0.0f}, b{0.0f};
    vec2 inward{0.0f};
    uint32_t mesh = 0, triangle = 0;  // the triangle it reads into (Scene::meshes, the mesh's own index)
};

struct LightmapSeam {
    SeamSide sides[2];
    double length = 0.0;       // in 3D, scene units (metres)
    float foldDegrees = 0.0f;  // the angle between the two triangles' planes (smooth-shaded folds)
};

// Seams. Among an atlas's meshes (their TEXCOORD_1), an edge shared by two triangles in 3D
// (both end positions equal once welded, to a millionth of the meshes' extent) whose uv1
// differs at either end. Only where the surface is smooth there: the two triangles' vertex
// normals agree at both ends within kSeamNormalDegrees (the bake shades texels with those
// normals, so the light is continuous there); a crease (a wall meeting the floor) has two
// values by right and is no seam. A fold of a smooth-shaded mesh (a low-poly cylinder, a
// rounded cushion) is a seam however sharp: it is shaded as one surface. Edges between
// different atlases are not seen here.
//
// The seams of an atlas of width × height texels holding `meshes` (indices into scene.meshes),
// in a fixed order (meshes, triangles and edges as stored).
std::vector<LightmapSeam> findLightmapSeams(const Scene& scene, const std::vector<uint32_t>& meshes, int width,
                                            int height);

struct SeamJump {
    size_t edges = 0;
    double length = 0.0;          // the seams' 3D length
    double meanRelative = 0.0;    // length-weighted mean of the pairs' relative jumps
    double pooledRelative = 0.0;  // Σ w|a − b| / Σ w (a + b)/2
    // The sums the two ratios come from, so atlases combine exactly: Σ w over the pairs
    // counted, Σ w · relative jump, Σ w|a − b| and Σ w (a + b)/2 (channels summed).
    double weight = 0.0, relativeSum = 0.0, jumpSum = 0.0, levelSum = 0.0;
};

// The jump. Along each seam, at evenly spaced points (about two per texel of its longer
// side), the lightmap is read bilinearly (as the viewer does, lightmap/lightmap_image.h) on both
// sides, `inset` texels inside each chart, perpendicular to the edge in texel space. A pair
// reads a and b (RGB); its relative jump is Σ|a − b| / Σ (a + b)/2 over the three channels.
// The figures: the mean of that over all pairs, each weighted by its share of its seam's 3D
// length; and the pooled ratio Σ w|a − b| / Σ w (a + b)/2, which counts a bright seam more.
//
// The jump is measured twice: half a texel in (the reads a texel apart in 3D, where a light
// that changes fast, as at a smooth-shaded fold, differs by right) and on the edge itself (the
// one point both sides stand for, where the light is one value: what a viewer shows as a line).
//
// `texels`: RGB, the atlas's size. Pairs black on both sides are left out.
SeamJump measureSeamJump(const std::vector<LightmapSeam>& seams, const Image& texels, float inset = kSeamInsetTexels);

// Stitching (after dilation): the texels that the seams' bilinear reads on the edge touch
// (covered ones and the padding ring beyond a chart's edge) move by a least-squares solve:
// minimise
//     Σ_pairs (bilinear_a(x) − bilinear_b(x))² + Σ_texels λ (x − baked)²
// subject to x ≥ 0, with λ = kStitchCoveredWeight for covered texels (stay near the bake) and
// kStitchPaddingWeight for padding ones (free to take what the seam needs). The pairs are read
// on the edge only: pairs half a texel in as well pulled a crease's dark texels to the bright
// side of a fold (the grey-white room's sofa, docs/seams.md). Direct and indirect are solved
// each, and the total is their sum again. Conjugate gradients with a diagonal
// preconditioner, in rounds that hold at zero what the last took below it; serial: the same
// bytes at any thread count (and in a cluster's merge, which calls the same finishLightmap).
//
// Stitches `direct` and `indirect` (RGB, the atlas's size, padding already dilated) along the
// seams and sets `total` = direct + indirect where they changed. mask: 1 channel, > 0.5
// covered. Returns the texels moved.
size_t stitchLightmapSeams(const std::vector<LightmapSeam>& seams, const Image& mask, Image& direct, Image& indirect,
                           Image& total);

// What bake.json reports of an atlas's seams: measured on the total as scene.glb carries it
// (lightmap/lightmap_image.h shippedLightmapTexels), before and after stitching.
struct LightmapSeamReport {
    bool stitched = false;
    size_t texelsMoved = 0;
    SeamJump before;       // half a texel in (kSeamInsetTexels)
    SeamJump after;        // = before when not stitched
    SeamJump beforeAtEdge;  // on the edge itself
    SeamJump afterAtEdge;
};

// An atlas's seams found, measured on its total as it ships, stitched when `stitch` says and
// measured again: what finishLightmap (bake.h) does after dilation. A `shadowmask` (RGBA,
// gather/shadowmask.h; may be null or empty) is stitched along the same seams by the same
// solve, and kept within 0..1.
LightmapSeamReport finishLightmapSeams(const Scene& scene, const std::vector<uint32_t>& meshes, const Image& mask,
                                       Image& direct, Image& indirect, Image& total, bool stitch,
                                       Image* shadowmask = nullptr);

// The pooled figures of several atlases (each atlas's jumps weighted by its seams' length).
LightmapSeamReport combineSeamReports(const std::vector<LightmapSeamReport>& reports);

}  // namespace vl
