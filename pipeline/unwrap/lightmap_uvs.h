// Lightmap UVs for meshes that have none: takes a Scene, the meshes lacking TEXCOORD_1 and an
// atlas size in texels, gives each of those meshes a TEXCOORD_1 (uv1) in one shared atlas.
//
// Charts: triangles joined across shared edges (positions welded exactly) while their normal
// stays within kChartAngleDegrees of the chart's first (largest) triangle, so projecting the
// chart flat along that normal stretches no triangle's area by more than 1/cos of it, and
// while their projection overlaps none the chart holds (a surface folding back under itself
// within the cone starts another chart). Each chart is projected onto the plane of that
// normal, turned to its smallest bounding rectangle, and packed at one world-space texel size
// for the whole scene (density uniform in world units), the smallest that fits, searched by
// bisection: rectangles (skyline) bracket it, then the charts' own texel footprints dropped
// column by column ("profiles", in four orientations) refine it, so triangular charts nest
// (zdm2: 47% → 53% covered at 1024², 55% → 64% at 2048²); every chart keeps kPaddingTexels
// empty texel on each side,
// so two charts' texels have at least 2 empty texels between them (issue 14's padding): a
// bilinear lookup at a chart's edge reaches one texel out, which the bake's dilation fills
// from that chart alone. Two texels a side (4 between) left nvpro's Cornell box at 59%
// covered, one 67%. Vertices shared by two charts are split
// (every attribute copied; Mesh::Source::vertices says where each came from, for glTF out).
//
// Why not Blender's Lightmap Pack (one chart per face): a wall of two triangles is then two
// islands with a seam of padding through it, at a texel density that varies from face to
// face (sixfold on nvpro's Cornell box), and it took 638 s on zdm2 against 0.15 s here
// (README).
#pragma once

#include "scene/scene.h"

#include <string>
#include <vector>

namespace vl {

constexpr float kChartAngleDegrees = 30.0f;
constexpr int kPaddingTexels = 1;
constexpr int kMaxAtlasSide = 8192;

struct LightmapUvReport {
    int width = 0, height = 0;  // the atlas, grown from the one asked for where the charts' padding overfilled it
    size_t meshes = 0;          // meshes given a uv1
    size_t charts = 0;
    double texelSize = 0.0;     // metres per texel (the scene's units)
    double occupancy = 0.0;     // charts' projected area / atlas area, in texels
    double maxStretch = 1.0;    // largest 3D area / projected area over triangles
    double meanStretch = 1.0;   // area-weighted
    double seconds = 0.0;
};

// Gives the meshes `meshes` (indices into scene.meshes) that have triangles a uv1 in one
// width × height atlas, or one doubled (up to kMaxAtlasSide a side) until the charts take at
// least a quarter of it at the smallest texel size that fits: thousands of small charts need
// room for their padding (the caller bakes at report.width × height). A uv1 those meshes
// already have is replaced, and other meshes are left as they are: the caller decides which
// to unwrap. SettingsError for an atlas under 16 texels a side or over 16384, or a mesh index
// out of range; Error when the charts fit no atlas of kMaxAtlasSide.
LightmapUvReport generateLightmapUvs(Scene& scene, const std::vector<uint32_t>& meshes, int width, int height);

// "lightmap UVs: 12 meshes, 340 charts, texel 1.2 cm, 71% of the atlas, stretch ≤ 1.15".
std::string describeLightmapUvs(const LightmapUvReport& report);

}  // namespace vl
