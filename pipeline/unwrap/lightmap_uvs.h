// Lightmap UVs for meshes that have none: takes a Scene, the meshes lacking TEXCOORD_1 and an
// atlas (a size in texels, or a texel size), gives each of those meshes a TEXCOORD_1 (uv1) in
// one shared atlas, at one world-space texel size for the whole scene.
//
// Charts are grown by normal, cut where their rectangle is mostly empty, merged where a
// conformal flattening keeps the same stretch bound, and packed; generateLightmapUvs says
// how. Why not Blender's Lightmap Pack (one chart per face): a wall of two triangles is then
// two islands with a seam of padding through it, at a texel density that varies from face to
// face, and it is far slower. Measurements of the charts: docs/atlas.md.
#pragma once

#include "scene/scene.h"

#include <string>
#include <vector>

namespace vl {

constexpr float kChartAngleDegrees = 30.0f;
// Two charts that meet along a hard crease, an edge whose triangles fold by more than
// kMergeFoldDegrees and whose vertex normals there differ by more than kSmoothShadingDegrees,
// do not merge: a bilinear read near the fold would mix the light of both faces (a sunlit
// sill's top into its shaded front), and a texel on the fold would hold their mean. The bake's
// seams (lightmap/lightmap_seams.h) call an edge smooth by the same normals.
constexpr float kMergeFoldDegrees = 45.0f;
constexpr float kSmoothShadingDegrees = 15.0f;
// Where keeping charts apart at hard creases makes the texels coarser than this many times the
// texel size the charts' area alone would give at 60% of the atlas (or does not fit at all),
// the charts merge across creases too, if that packs finer (LightmapUvReport::mergedAcrossCreases).
constexpr double kCreaseTexelCost = 1.25;
constexpr int kPaddingTexels = 1;
constexpr int kMaxAtlasSide = 8192;
// The largest atlas a side that an atlas sized for the bake (`lightmap-res auto`) gets.
constexpr int kMaxAutoAtlasSide = 4096;
// A merged chart may not grow longer than this share of the side of the square its scene's
// charts would fill at 60% (a room's walls unrolled into one strip would set the texel size),
// or than its longer part by more than a few percent.
constexpr double kMergeLengthShare = 0.5;
// A chart under this many texels along either side of its rectangle is reported.
constexpr double kSmallChartTexels = 2.0;

// The atlas asked for: exactly width × height texels (the texel size chosen so the charts fit),
// or with texelSize > 0 that many metres (scene units) per texel and the smallest square atlas,
// a multiple of 4 texels a side, that holds the charts at it, up to maxSide; where even
// maxSide² does not hold them, maxSide² at the texel size that fits (report.texelSize says).
// powerOfTwo: the smallest power-of-two square instead, at the texel size that fills it
// (texelSize or finer).
struct AtlasRequest {
    int width = 256, height = 256;
    double texelSize = 0.0;
    int maxSide = kMaxAtlasSide;
    bool powerOfTwo = false;
};

struct SmallCharts {
    std::string mesh;  // Mesh::name
    size_t charts = 0;
};

struct LightmapUvReport {
    int width = 0, height = 0;  // the atlas: the one asked for, or sized for the texel size asked
    size_t meshes = 0;          // meshes given a uv1
    size_t charts = 0;
    size_t grownCharts = 0;     // charts before merging
    double texelSize = 0.0;     // metres per texel (the scene's units)
    double askedTexelSize = 0.0;  // AtlasRequest::texelSize (0: an atlas size was asked)
    double occupancy = 0.0;     // charts' flattened area / atlas area, in texels
    double maxStretch = 1.0;    // largest 3D area / flattened area over triangles, at the texel size
    double meanStretch = 1.0;   // area-weighted
    bool mergedAcrossCreases = false;  // the atlas asked could not keep them apart (kCreaseTexelCost)
    // Charts under kSmallChartTexels along a side that no neighbour could take, per mesh (most first).
    std::vector<SmallCharts> smallCharts;
    size_t smallChartCount() const;
    double seconds = 0.0;
};

// Charts, in three steps:
// - Grown: triangles joined across shared edges (positions welded exactly) while their normal
//   stays within kChartAngleDegrees of the chart's first (largest) triangle, so projecting the
//   chart flat along that normal stretches no triangle's area by more than 1/cos of it, and
//   while their projection overlaps none the chart holds (a surface folding back under itself
//   within the cone starts another chart).
// - Cut: a chart whose rectangle is more than half empty (a frame round a room) is cut in two
//   along itself, again and again, where the parts pack into fewer texels.
// - Merged: neighbouring charts become one where the union, flattened conformally
//   (unwrap/flatten.h), keeps every triangle's area stretch within the same bound, folds no
//   triangle over and overlaps nothing, and its bounding rectangle, padding included, is
//   little larger than its parts' and no longer than kMergeLengthShare allows. Greedy growth
//   on a smooth but curved surface (the grey-white room's cushions) left pockets between the
//   cones as charts of their own, each with its padding; a strip folded smoothly off a face (a
//   rounded edge) unfolds into it with no stretch at all. Smaller charts merge first, each
//   with the neighbour it shares the longest edge with. Charts that meet at a hard crease
//   (kMergeFoldDegrees) stay apart unless the atlas cannot afford it (kCreaseTexelCost).
// A chart still under kSmallChartTexels along a side at the texel size packed is reported.
//
// Each chart is turned to its smallest bounding rectangle and packed at one world-space texel
// size for the whole scene (density uniform in world units): for an atlas of a given size the
// smallest that fits, searched by bisection (rectangles (skyline) bracket it, then the charts'
// own texel footprints dropped column by column ("profiles", in four orientations) refine it,
// so triangular charts nest); for a texel size, the smallest square atlas (a multiple of 4
// texels a side) that holds them. Every chart keeps kPaddingTexels empty texel on each side,
// so two charts' texels have at least 2 empty texels between them (issue 14's padding): a
// bilinear lookup at a chart's edge reaches one texel out, which the bake's dilation fills
// from that chart alone; two a side would cost a small atlas much of its coverage. Vertices
// shared by two charts are split (every attribute copied; Mesh::Source::vertices says where
// each came from, for glTF out).
//
// Gives the meshes `meshes` (indices into scene.meshes) that have triangles a uv1 in one atlas
// as `atlas` asks (the caller bakes at report.width × height). A uv1 those meshes already have
// is replaced, and other meshes are left as they are: the caller decides which to unwrap.
// SettingsError for an atlas under 16 texels a side or over 16384, a texel size that is not
// positive and finite, a mesh index out of range, or charts that fit the atlas asked at no
// texel size (each needs its padding).
LightmapUvReport generateLightmapUvs(Scene& scene, const std::vector<uint32_t>& meshes, const AtlasRequest& atlas);
// Exactly width × height.
LightmapUvReport generateLightmapUvs(Scene& scene, const std::vector<uint32_t>& meshes, int width, int height);

// "lightmap UVs: 12 meshes, 340 charts, texel 1.2 cm, 71% of the atlas, stretch ≤ 1.15".
std::string describeLightmapUvs(const LightmapUvReport& report);

}  // namespace vl
