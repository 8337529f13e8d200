// Lightmap chart seams (lightmap/lightmap_seams.h): which edges are seams, the jump measured
// across them against hand-computed values, stitching a step away, and a bake of a floor
// split into two charts whose seam disappears when stitched.
#include "bake/bake.h"
#include "lightmap/dilate.h"
#include "lightmap/lightmap_image.h"
#include "lightmap/lightmap_seams.h"
#include "quad_scene.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;
using namespace vl::test;

namespace {

// Appends a rectangle p0 p1 p2 p3 (counter-clockwise seen from its normal's side) to `mesh` as
// two triangles, its corners at texel coordinates t0..t3 of a size × size atlas: a chart of its
// own (its vertices are not shared with any other rectangle's, only their positions).
void addChart(Mesh& mesh, const std::array<vec3, 4>& p, const std::array<vec2, 4>& t, int size) {
    const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    const vec3 n = glm::normalize(glm::cross(p[1] - p[0], p[3] - p[0]));
    for (int k = 0; k < 4; ++k) {
        mesh.positions.push_back(p[size_t(k)]);
        mesh.normals.push_back(n);
        mesh.uv1.push_back(t[size_t(k)] / float(size));
    }
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) mesh.indices.push_back(base + i);
}

// Texel corners of the rectangle [x0, x1] × [y0, y1], in the order p0..p3 of a rectangle whose
// p0→p1 runs along its second axis (z) and p0→p3 along its first (x): x maps to texel x, z to
// texel y.
std::array<vec2, 4> texelRect(float x0, float y0, float x1, float y1) {
    return {vec2(x0, y0), vec2(x0, y1), vec2(x1, y1), vec2(x1, y0)};
}

// A floor rectangle [x0, x1] × [z0, z1] at height y, facing +Y.
std::array<vec3, 4> floorRect(float x0, float z0, float x1, float z1, float y = 0.0f) {
    return {vec3(x0, y, z0), vec3(x0, y, z1), vec3(x1, y, z1), vec3(x1, y, z0)};
}

constexpr int kAtlas = 32;

// Two flat surfaces, each split into two charts, and a wall standing on the first's edge:
//   A | B: [0,1] × [0,1] and [1,2] × [0,1], a seam 1 m long, charts at texels [2,10]² and
//          [14,22] × [2,10] (8 texels a metre);
//   C | D: [0,1] × [0,3] and [1,2] × [0,3] at y = 5, a seam 3 m long, charts at texels
//          [2,6] × [14,26] and [10,14] × [14,26] (4 texels a metre);
//   a wall at x = 2 on B's far edge, facing +X, its own chart: a crease, no seam.
Scene twoSplitSurfaces() {
    Scene scene;
    scene.sourcePath = "split surfaces (test)";
    const int white = addLambert(scene, vec3(0.8f));
    Mesh mesh;
    mesh.name = "floor";
    mesh.material = white;
    addChart(mesh, floorRect(0, 0, 1, 1), texelRect(2, 2, 10, 10), kAtlas);
    addChart(mesh, floorRect(1, 0, 2, 1), texelRect(14, 2, 22, 10), kAtlas);
    addChart(mesh, floorRect(0, 0, 1, 3, 5), texelRect(2, 14, 6, 26), kAtlas);
    addChart(mesh, floorRect(1, 0, 2, 3, 5), texelRect(10, 14, 14, 26), kAtlas);
    addChart(mesh, {vec3(2, 0, 0), vec3(2, 1, 0), vec3(2, 1, 1), vec3(2, 0, 1)}, texelRect(26, 2, 30, 6), kAtlas);
    scene.meshes.push_back(mesh);
    return scene;
}

// The texels of the charts above (mask) and a lightmap of `values` per chart A, B, C, D and
// the wall, padding dilated.
struct SyntheticAtlas {
    Image mask{kAtlas, kAtlas, 1};
    Image texels{kAtlas, kAtlas, 3};
};
SyntheticAtlas syntheticAtlas(const std::array<float, 5>& values) {
    SyntheticAtlas atlas;
    const int rects[5][4] = {{2, 2, 10, 10}, {14, 2, 22, 10}, {2, 14, 6, 26}, {10, 14, 14, 26}, {26, 2, 30, 6}};
    for (int r = 0; r < 5; ++r)
        for (int y = rects[r][1]; y < rects[r][3]; ++y)
            for (int x = rects[r][0]; x < rects[r][2]; ++x) {
                atlas.mask.at(x, y) = 1.0f;
                atlas.texels.setRgb(x, y, vec3(values[size_t(r)]));
            }
    dilatePadding(atlas.texels, atlas.mask);
    return atlas;
}

}  // namespace

TEST_CASE("A seam is an edge one in 3D and two in the atlas, where the surface is smooth", "[bake]") {
    const Scene scene = twoSplitSurfaces();
    const std::vector<LightmapSeam> seams = findLightmapSeams(scene, {0}, kAtlas, kAtlas);
    // The two splits; not the triangles' diagonals (one chart), nor the wall's edge on B (a crease).
    REQUIRE(seams.size() == 2);
    CHECK(seams[0].length + seams[1].length == Approx(4.0));
    for (const LightmapSeam& seam : seams)
        for (const SeamSide& side : seam.sides) CHECK(glm::length(side.inward) == Approx(1.0f));

    // The same floor with a hard edge along the first split (the normals differ at its ends)
    // is a crease there.
    Scene hard = scene;
    for (size_t v = 4; v < 8; ++v) hard.meshes[0].normals[v] = glm::normalize(vec3(0.5f, 1.0f, 0.0f));
    CHECK(findLightmapSeams(hard, {0}, kAtlas, kAtlas).size() == 1);
}

TEST_CASE("The seam jump is the length-weighted relative difference read across each seam", "[bake]") {
    const Scene scene = twoSplitSurfaces();
    const std::vector<LightmapSeam> seams = findLightmapSeams(scene, {0}, kAtlas, kAtlas);
    // A reads 1 and B 2 along the 1 m seam: |1 − 2| / 1.5 = 2/3; C and D read 1 and 1 along the
    // 3 m seam: 0. Half a texel in, every read stays inside its chart's constant texels.
    const SyntheticAtlas atlas = syntheticAtlas({1.0f, 2.0f, 1.0f, 1.0f, 5.0f});
    const SeamJump jump = measureSeamJump(seams, atlas.texels);
    CHECK(jump.edges == 2);
    CHECK(jump.length == Approx(4.0));
    CHECK(jump.meanRelative == Approx((1.0 * 2.0 / 3.0 + 3.0 * 0.0) / 4.0));
    // Pooled: Σ w|a − b| / Σ w (a + b)/2 over RGB: (1 · 3) / (1 · 4.5 + 3 · 3).
    CHECK(jump.pooledRelative == Approx(3.0 / 13.5));

    // Both seams stepped: C 1, D 3 → |1 − 3| / 2 = 1 over 3 m.
    const SeamJump both = measureSeamJump(seams, syntheticAtlas({1.0f, 2.0f, 1.0f, 3.0f, 5.0f}).texels);
    CHECK(both.meanRelative == Approx((1.0 * 2.0 / 3.0 + 3.0 * 1.0) / 4.0));

    // Atlases combine by their seams' length.
    LightmapSeamReport a, b;
    a.before = a.after = jump;
    b.before = b.after = both;
    const LightmapSeamReport combined = combineSeamReports({a, b});
    CHECK(combined.after.edges == 4);
    CHECK(combined.after.meanRelative == Approx((jump.meanRelative + both.meanRelative) / 2.0));
}

TEST_CASE("Stitching makes a step across a seam one value on the edge, in direct, indirect and total alike", "[bake]") {
    const Scene scene = twoSplitSurfaces();
    const std::vector<LightmapSeam> seams = findLightmapSeams(scene, {0}, kAtlas, kAtlas);
    const SyntheticAtlas atlas = syntheticAtlas({1.0f, 2.0f, 1.0f, 3.0f, 5.0f});
    Image direct = atlas.texels, indirect = atlas.texels;
    for (float& v : direct.pixels) v *= 0.25f;
    for (float& v : indirect.pixels) v *= 0.75f;
    Image total = direct;
    for (size_t i = 0; i < total.pixels.size(); ++i) total.pixels[i] += indirect.pixels[i];
    const double before = measureSeamJump(seams, total, 0.0f).meanRelative;

    Image stitchedDirect = direct, stitchedIndirect = indirect, stitchedTotal = total;
    const size_t moved = stitchLightmapSeams(seams, atlas.mask, stitchedDirect, stitchedIndirect, stitchedTotal);
    const double after = measureSeamJump(seams, stitchedTotal, 0.0f).meanRelative;
    WARN("step across both seams: mean relative jump on the edge " << before << " before stitching, " << after
                                                                   << " after, " << moved << " texels moved");
    CHECK(before > 0.5);
    CHECK(after < 0.02);
    for (size_t i = 0; i < total.pixels.size(); ++i)
        REQUIRE(stitchedTotal.pixels[i] == stitchedDirect.pixels[i] + stitchedIndirect.pixels[i]);

    // A | B is its own mirror image (1 m, 8 texels a metre on both sides, 1 against 2): on the
    // edge the two sides meet halfway, 1.5, at the seam's middle, and what A gains B loses.
    // The padding beyond each chart's edge takes the step; the covered texels, half a texel
    // in, keep all but a few percent of it.
    const LightmapSeam& ab = seams[0].length < seams[1].length ? seams[0] : seams[1];
    REQUIRE(ab.length == Approx(1.0));
    for (const SeamSide& side : ab.sides) {
        const vec2 middle = 0.5f * (side.a + side.b);
        const vec3 read = sampleLightmap(stitchedTotal, middle / float(kAtlas));
        CHECK(read.x == Approx(1.5).epsilon(0.02));
        CHECK(read.y == Approx(1.5).epsilon(0.02));
        const vec2 inside = middle + kSeamInsetTexels * side.inward;
        const float baked = sampleLightmap(total, inside / float(kAtlas)).x;
        CHECK(std::abs(sampleLightmap(stitchedTotal, inside / float(kAtlas)).x - baked) < 0.1f);
    }
    double change = 0.0, movement = 0.0;
    for (int y = 2; y < 10; ++y)
        for (int x = 2; x < 22; ++x)
            if (atlas.mask.at(x, y) > 0.5f) {
                change += stitchedTotal.at(x, y) - total.at(x, y);
                movement += std::abs(stitchedTotal.at(x, y) - total.at(x, y));
            }
    // The covered edge texels take a share of the step too: their λ is 25 times the padding's,
    // not infinite.
    CHECK(movement > 0.3);
    CHECK(std::abs(change) < 0.02 * movement);
    // The wall's chart (no seam) and the charts' far sides keep their baked values.
    CHECK(stitchedTotal.rgb(28, 4) == total.rgb(28, 4));
    CHECK(stitchedTotal.rgb(3, 5) == total.rgb(3, 5));
    CHECK(stitchedTotal.rgb(20, 5) == total.rgb(20, 5));
    // Deterministic: the same bytes again.
    Image again = direct, againIndirect = indirect, againTotal = total;
    stitchLightmapSeams(seams, atlas.mask, again, againIndirect, againTotal);
    CHECK(againTotal.pixels == stitchedTotal.pixels);
}

TEST_CASE("Stitching meets a step against a dark side without going below zero", "[bake]") {
    // A floor split at x = 1 into two charts whose edges in the atlas sit three quarters into
    // their last covered texels: A's at texel x 9.75 (texels 2..9 covered, 1 baked), B's at
    // 14.25 (texels 14..21, 0.1 baked). On the edge each side reads ¾ of its own covered texel
    // and ¼ of the padding beyond it. Left unbounded, the least squares meets the sides by
    // taking A's padding to about −0.8 and B's up by as much; light cannot be negative, and
    // clamping that afterwards pulls the sides apart again. Bounded, A's padding stops at zero
    // and B's rises further: the two meet.
    Scene scene;
    scene.sourcePath = "split floor, edges inside texels (test)";
    const int white = addLambert(scene, vec3(0.8f));
    Mesh mesh;
    mesh.name = "floor";
    mesh.material = white;
    addChart(mesh, floorRect(0, 0, 1, 1), texelRect(2.0f, 2, 9.75f, 10), kAtlas);
    addChart(mesh, floorRect(1, 0, 2, 1), texelRect(14.25f, 2, 22, 10), kAtlas);
    scene.meshes.push_back(mesh);
    const std::vector<LightmapSeam> seams = findLightmapSeams(scene, {0}, kAtlas, kAtlas);
    REQUIRE(seams.size() == 1);

    Image mask(kAtlas, kAtlas, 1), direct(kAtlas, kAtlas, 3);
    for (int y = 2; y < 10; ++y)
        for (int x = 2; x < 22; ++x) {
            if (x >= 10 && x < 14) continue;
            mask.at(x, y) = 1.0f;
            direct.setRgb(x, y, vec3(x < 10 ? 1.0f : 0.1f));
        }
    dilatePadding(direct, mask);
    Image indirect(kAtlas, kAtlas, 3), total = direct;
    const double before = measureSeamJump(seams, total, 0.0f).meanRelative;
    const size_t moved = stitchLightmapSeams(seams, mask, direct, indirect, total);
    const double after = measureSeamJump(seams, total, 0.0f).meanRelative;
    WARN("step 1 | 0.1, edges inside texels: jump on the edge " << before << " before stitching, " << after
                                                                 << " after, " << moved << " texels moved");
    // |1 − 0.1| / 0.55 before.
    CHECK(before == Approx(0.9 / 0.55).epsilon(0.01));
    CHECK(after < 0.02);
    for (const Image* image : {&direct, &indirect, &total})
        for (float v : image->pixels) REQUIRE(v >= 0.0f);
    // A's padding is held at zero, and its covered edge texel stays on its own side of the
    // step's midpoint (0.55): B's padding, 25 times freer, takes the most of the step.
    CHECK(direct.at(10, 5) == 0.0f);
    CHECK(direct.at(9, 5) > 0.55f);
    CHECK(direct.at(13, 5) > 1.0f);
}

TEST_CASE("Stitching a lightmap smooth across its seams moves it by less than a texel's step", "[bake]") {
    const Scene scene = twoSplitSurfaces();
    const std::vector<LightmapSeam> seams = findLightmapSeams(scene, {0}, kAtlas, kAtlas);
    // 1 + x over A | B (x in metres, texel centres), 1 + z/3 over C | D: the light each texel
    // centre of the split surfaces would have, continuous across the seams. A texel's step is
    // 1/8 along x on A | B and 1/12 along z on C | D (along the seam, so no step across it).
    const SyntheticAtlas atlas = syntheticAtlas({1.0f, 1.0f, 1.0f, 1.0f, 5.0f});
    Image direct = atlas.texels;
    for (int y = 0; y < kAtlas; ++y)
        for (int x = 0; x < kAtlas; ++x) {
            if (atlas.mask.at(x, y) < 0.5f || x >= 26) continue;
            const float u = float(x) + 0.5f, v = float(y) + 0.5f;
            float value = 0.0f;
            if (y < 12) value = 1.0f + (x < 12 ? (u - 2.0f) / 8.0f : 1.0f + (u - 14.0f) / 8.0f);
            else value = 1.0f + (v - 14.0f) / 4.0f / 3.0f;
            direct.setRgb(x, y, vec3(value));
        }
    for (float& v : direct.pixels) v = std::max(v, 0.0f);
    Image mask = atlas.mask;
    dilatePadding(direct, mask);
    Image indirect(kAtlas, kAtlas, 3), total = direct;
    const double before = measureSeamJump(seams, total).meanRelative;

    Image stitchedDirect = direct, stitchedIndirect = indirect, stitchedTotal = total;
    stitchLightmapSeams(seams, mask, stitchedDirect, stitchedIndirect, stitchedTotal);
    // Read half a texel in on each side, A | B's two reads are a texel apart in 3D: 1/8 apart,
    // 0.125 / 2 relative over its quarter of the seams' length; C | D reads one value.
    CHECK(before == Approx(0.25 * 0.125 / 2.0).epsilon(0.05));
    CHECK(measureSeamJump(seams, stitchedTotal).meanRelative < before);
    float most = 0.0f;
    for (int y = 0; y < kAtlas; ++y)
        for (int x = 0; x < kAtlas; ++x)
            if (mask.at(x, y) > 0.5f) most = std::max(most, std::abs(stitchedTotal.at(x, y) - total.at(x, y)));
    CHECK(most > 0.0f);
    CHECK(most < 0.125f);
    for (int y = 14; y < 26; ++y)
        for (int x = 2; x < 14; ++x)
            if (mask.at(x, y) > 0.5f) CHECK(stitchedTotal.at(x, y) == Approx(total.at(x, y)).margin(1e-3));
}

namespace {

// A closed 2 m room lit by a point light under its ceiling, its floor split at x = 1 into two
// charts of one 32² image: x ∈ [0,1] at 8 texels a metre, x ∈ [1,2] turned a quarter and at 6,
// so the two sides of the split read different texel lattices.
Scene roomWithSplitFloor() {
    Scene scene;
    scene.sourcePath = "room with a split floor (test)";
    const int white = addLambert(scene, vec3(0.7f));
    addRoom(scene, "room/", white, vec3(0.0f), vec3(2.0f));
    scene.meshes.erase(scene.meshes.begin());  // the room's own floor
    Mesh floor;
    floor.name = "split floor";
    floor.material = white;
    addChart(floor, floorRect(0, 0, 1, 2), texelRect(2, 2, 10, 18), kAtlas);
    // x → texel y (downward from 20), z → texel x: turned a quarter.
    addChart(floor, floorRect(1, 0, 2, 2), {vec2(2, 20), vec2(14, 20), vec2(14, 26), vec2(2, 26)}, kAtlas);
    scene.meshes.push_back(floor);
    scene.lights.push_back(pointLightAt(vec3(0.7f, 1.6f, 0.9f), 2.0f));
    return scene;
}

BakeSettings splitFloorSettings(bool stitch) {
    BakeSettings settings = quietSettings();
    settings.voxel.resolution = 32;
    settings.lightmap.atlasPerMesh = true;
    settings.lightmap.width = settings.lightmap.height = kAtlas;
    settings.lightmapStitch = stitch;
    return settings;
}

const BakedLightmap& floorLightmap(const BakeResult& result) {
    for (const BakedLightmap& l : result.lightmaps)
        if (l.name == "split floor") return l;
    FAIL("no floor lightmap");
    return result.lightmaps.front();
}

}  // namespace

TEST_CASE("A floor split into two charts shows one value along the split once stitched", "[bake]") {
    const Scene scene = roomWithSplitFloor();
    const BakeResult stitched = bakeOnThreads(scene, splitFloorSettings(true), 2);
    const BakeResult plain = bakeOnThreads(scene, splitFloorSettings(false), 2);
    const LightmapSeamReport& on = floorLightmap(stitched).seams;
    const LightmapSeamReport& off = floorLightmap(plain).seams;
    WARN("split floor: mean relative jump on the edge " << off.afterAtEdge.meanRelative << " unstitched, "
                                                        << on.afterAtEdge.meanRelative << " stitched ("
                                                        << on.beforeAtEdge.meanRelative << " before)");
    REQUIRE(on.after.edges == 1);  // the split: one triangle edge on either side
    CHECK(on.stitched);
    CHECK_FALSE(off.stitched);
    CHECK(off.after.meanRelative == off.before.meanRelative);
    CHECK(off.afterAtEdge.meanRelative == off.beforeAtEdge.meanRelative);
    CHECK(on.before.meanRelative == off.after.meanRelative);
    CHECK(on.afterAtEdge.meanRelative <= 0.02);
    CHECK(off.afterAtEdge.meanRelative > 2.0 * on.afterAtEdge.meanRelative);
    // Half a texel in, the reads stand for points a texel apart, and keep most of their
    // difference: the stitch moves the covered texels by little.
    CHECK(on.after.meanRelative > 0.5 * on.before.meanRelative);

    // total = direct + indirect: exactly where stitched or covered, to rounding in padding
    // (dilation averages the three images each on its own).
    const BakedLightmap& floor = floorLightmap(stitched);
    for (size_t i = 0; i < floor.total.pixels.size(); ++i)
        REQUIRE(floor.total.pixels[i] == Approx(floor.direct.pixels[i] + floor.indirect.pixels[i]).epsilon(1e-6));
    // Stitching moves texels within a texel or two of the 2 m seam by about half its 3 % jump:
    // the floor's light as a whole stays where the bake put it.
    double stitchedSum = 0.0, plainSum = 0.0;
    const BakedLightmap& plainFloor = floorLightmap(plain);
    for (size_t t = 0; t < floor.mask.pixels.size(); ++t)
        if (floor.mask.pixels[t] > 0.5f)
            for (size_t c = 0; c < 3; ++c) {
                stitchedSum += floor.total.pixels[3 * t + c];
                plainSum += plainFloor.total.pixels[3 * t + c];
            }
    CHECK(plainSum > 0.0);
    CHECK(stitchedSum == Approx(plainSum).epsilon(0.005));
    // The walls have no seam: stitching leaves them as they were.
    for (size_t l = 0; l < stitched.lightmaps.size(); ++l)
        if (stitched.lightmaps[l].name != "split floor") CHECK(stitched.lightmaps[l].total.pixels == plain.lightmaps[l].total.pixels);

    // The same bytes on one thread.
    const BakeResult one = bakeOnThreads(scene, splitFloorSettings(true), 1);
    CHECK(floorLightmap(one).total.pixels == floor.total.pixels);
}
