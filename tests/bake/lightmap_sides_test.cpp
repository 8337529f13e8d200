// Which side of a double-sided surface a lightmap holds (receivers/lightmap_sides.h): a lid closing a
// black box, its front facing the sky. Under a uniform sky of radiance L its top receives π L
// (texel L) and its underside nothing (the box is closed and black): the setting picks which.
#include "bake/bake.h"
#include "receivers/receivers.h"
#include "core/error.h"
#include "quad_scene.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;
using namespace vl::test;

namespace {

// A box's floor and four walls over [lo, hi], facing in; no top.
void addBoxFacingIn(Scene& scene, int material, const vec3& lo, const vec3& hi) {
    const vec3 p000(lo.x, lo.y, lo.z), p100(hi.x, lo.y, lo.z), p010(lo.x, hi.y, lo.z), p110(hi.x, hi.y, lo.z);
    const vec3 p001(lo.x, lo.y, hi.z), p101(hi.x, lo.y, hi.z), p011(lo.x, hi.y, hi.z), p111(hi.x, hi.y, hi.z);
    addQuad(scene, "floor", material, p000, p001, p101, p100);
    addQuad(scene, "wall-x", material, p000, p010, p011, p001);
    addQuad(scene, "wall+x", material, p100, p101, p111, p110);
    addQuad(scene, "wall-z", material, p000, p100, p110, p010);
    addQuad(scene, "wall+z", material, p001, p011, p111, p101);
}

// The 2 m room's ceiling at y = 2 round a 1 m skylight, normals −Y (facing into the room).
void addCeilingRoundSkylight(Scene& scene, int material) {
    const float s = 1.0f, h = 2.0f, w = 0.5f;
    addQuad(scene, "ceiling-z", material, {-s, h, -s}, {s, h, -s}, {s, h, -w}, {-s, h, -w});
    addQuad(scene, "ceiling+z", material, {-s, h, w}, {s, h, w}, {s, h, s}, {-s, h, s});
    addQuad(scene, "ceiling-x", material, {-s, h, -w}, {-w, h, -w}, {-w, h, w}, {-s, h, w});
    addQuad(scene, "ceiling+x", material, {w, h, -w}, {s, h, -w}, {s, h, w}, {w, h, w});
}

// A camera standing in the 2 m room, looking at its wall at z = −1.
void addRoomCamera(Scene& scene) {
    Camera camera;
    camera.position = vec3(0.0f, 1.0f, 0.9f);
    camera.forward = vec3(0.0f, 0.0f, -1.0f);
    scene.cameras.push_back(camera);
}

Scene lidOnABlackBox() {
    Scene scene;
    const int black = addLambert(scene, vec3(0.0f));
    const int lid = addLambert(scene, vec3(0.5f));
    scene.materials[size_t(lid)].doubleSided = true;
    // The box's floor and four walls, facing in; no ceiling: the lid closes it.
    addBoxFacingIn(scene, black, vec3(-0.5f, 0.0f, -0.5f), vec3(0.5f, 0.4f, 0.5f));
    addQuad(scene, "lid", lid, {-0.5f, 0.4f, -0.5f}, {-0.5f, 0.4f, 0.5f}, {0.5f, 0.4f, 0.5f},
            {0.5f, 0.4f, -0.5f});  // normal +Y: its front faces the sky
    return scene;
}

// The 32² lightmap of the mesh named `mesh`, baked under a uniform sky of radiance 1 alone.
BakedLightmap meshLightmapUnderSky(const Scene& scene, LightmapSide side, const std::string& mesh) {
    BakeSettings settings = quietSettings();
    settings.sky = vec3(1.0f);
    settings.lightmap.atlasPerMesh = true;
    settings.lightmap.width = settings.lightmap.height = 32;
    settings.lightmapSide = side;
    Diagnostics diagnostics(false, false);
    const BakeResult result = bake(scene, settings, diagnostics);
    for (const BakedLightmap& lightmap : result.lightmaps)
        if (lightmap.name.find(mesh) != std::string::npos) return lightmap;
    FAIL("no lightmap named " << mesh);
    return {};
}

// The mean (green) of a 32² lightmap's middle 4 × 4 texels.
double centreTexels(const BakedLightmap& lightmap) {
    double sum = 0.0;
    for (int y = 14; y < 18; ++y)
        for (int x = 14; x < 18; ++x) sum += lightmap.total.at(x, y, 1);
    return sum / 16.0;
}

// The lid's lightmap: its covered texels' mean and extremes (green).
struct LidTexels {
    double mean = 0.0, lowest = 1e30, highest = -1e30;
    size_t count = 0;
};

LidTexels lidTexels(LightmapSide side) {
    const BakedLightmap lightmap = meshLightmapUnderSky(lidOnABlackBox(), side, "lid");
    LidTexels lid;
    for (int y = 0; y < lightmap.mask.height; ++y)
        for (int x = 0; x < lightmap.mask.width; ++x) {
            if (lightmap.mask.at(x, y) < 0.5f) continue;
            const double v = lightmap.total.at(x, y, 1);
            lid.mean += v;
            lid.lowest = std::min(lid.lowest, v);
            lid.highest = std::max(lid.highest, v);
            ++lid.count;
        }
    if (lid.count) lid.mean /= double(lid.count);
    return lid;
}

// A black room [−1, 1] × [0, 2] × [−1, 1] whose faces are wound outward, as exporters leave some
// rooms (from within, every wall is a back face, as a closed solid's inside is), with a 1 m
// skylight in its ceiling and a camera in it. On its floor, 1 cm up, lies a double-sided rug
// wound facing down. The room is seen from within: the rug's lightmap must hold its top.
Scene rugInARoomWoundOutward() {
    Scene scene;
    const int black = addLambert(scene, vec3(0.0f));
    const int rug = addLambert(scene, vec3(0.5f));
    scene.materials[size_t(black)].doubleSided = true;
    scene.materials[size_t(rug)].doubleSided = true;
    const float s = 1.0f, h = 2.0f, w = 0.5f;  // half width, height, the skylight's half width
    const vec3 p000(-s, 0, -s), p100(s, 0, -s), p010(-s, h, -s), p110(s, h, -s);
    const vec3 p001(-s, 0, s), p101(s, 0, s), p011(-s, h, s), p111(s, h, s);
    // Each quad's corners counter-clockwise seen from outside the room.
    addQuad(scene, "floor", black, p000, p100, p101, p001);
    addQuad(scene, "wall-x", black, p000, p001, p011, p010);
    addQuad(scene, "wall+x", black, p100, p110, p111, p101);
    addQuad(scene, "wall-z", black, p000, p010, p110, p100);
    addQuad(scene, "wall+z", black, p001, p101, p111, p011);
    // The ceiling round the skylight, normals +Y.
    addQuad(scene, "ceiling-z", black, {-s, h, -s}, {-s, h, -w}, {s, h, -w}, {s, h, -s});
    addQuad(scene, "ceiling+z", black, {-s, h, w}, {-s, h, s}, {s, h, s}, {s, h, w});
    addQuad(scene, "ceiling-x", black, {-s, h, -w}, {-s, h, w}, {-w, h, w}, {-w, h, -w});
    addQuad(scene, "ceiling+x", black, {w, h, -w}, {w, h, w}, {s, h, w}, {s, h, -w});
    const float y = 0.01f, r = 0.4f;
    addQuad(scene, "rug", rug, {-r, y, -r}, {r, y, -r}, {r, y, r}, {-r, y, r});  // normal −Y
    addRoomCamera(scene);
    return scene;
}

}  // namespace

TEST_CASE("A rug in a room wound outward: inside holds the top its camera sees, lit through the skylight", "[bake]") {
    // The top sees the sky only through the skylight, a centred square of half width a at
    // height d: at the rug's centre the texel is L × the form factor 4 F(a/d, a/d), with
    // F(X, Y) = [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))] / 2π.
    const double a = 0.5, d = 2.0 - 0.01, X = a / d, q = std::sqrt(1.0 + X * X);
    const double centre = 4.0 * 2.0 * X / q * std::atan(X / q) / (2.0 * 3.14159265358979);  // 0.0742
    const Scene scene = rugInARoomWoundOutward();
    for (LightmapSide side : {LightmapSide::Front, LightmapSide::Inside}) {
        const BakedLightmap lightmap = meshLightmapUnderSky(scene, side, "rug");
        // The middle 4 × 4 texels: 10 cm across, where the form factor changes by < 1%.
        const double mean = centreTexels(lightmap);
        INFO(toString(side) << ": centre " << mean << ", the skylight's form factor " << centre);
        if (side == LightmapSide::Front)
            CHECK(mean < 0.01 * centre);  // the underside, a centimetre over a black floor
        else
            CHECK(mean == Approx(centre).epsilon(0.05));
    }
}

TEST_CASE("A double-sided lid on a black box: inside holds its dark underside, front its sunlit top", "[bake]") {
    const LidTexels front = lidTexels(LightmapSide::Front), inside = lidTexels(LightmapSide::Inside);
    REQUIRE(front.count > 500);
    REQUIRE(inside.count == front.count);
    INFO("front " << front.lowest << " … " << front.highest << ", inside " << inside.lowest << " … " << inside.highest);
    // The top sees the whole sky and nothing above it: L at every texel.
    CHECK(front.lowest == Approx(1.0).epsilon(1e-3));
    CHECK(front.highest == Approx(1.0).epsilon(1e-3));
    // The underside sees the closed black box: no light, but for the rim's texels, whose rays
    // start a hair from the walls' edges and find the crack there (0.2% of L measured).
    CHECK(inside.mean < 1e-3);
    CHECK(inside.highest < 0.01);
}

namespace {

// A black room [−1, 1] × [0, 2] × [−1, 1] wound inward, with a 1 m skylight in its ceiling and a
// camera in it. On the wall at z = −1 hangs a double-sided panel (a picture's frame), 5 mm off
// the plaster, 0.6 m square, wound facing the wall: its front sees the plaster, its back the room.
Scene panelAgainstAWall() {
    Scene scene;
    const int black = addLambert(scene, vec3(0.0f));
    const int panel = addLambert(scene, vec3(0.5f));
    scene.materials[size_t(panel)].doubleSided = true;
    const float s = 1.0f, h = 2.0f;
    addBoxFacingIn(scene, black, vec3(-s, 0.0f, -s), vec3(s, h, s));
    // The ceiling round the skylight, normals −Y.
    addCeilingRoundSkylight(scene, black);
    const float z = -s + 0.005f, r = 0.3f, y0 = 0.7f, y1 = 1.3f;
    addQuad(scene, "panel", panel, {-r, y0, z}, {-r, y1, z}, {r, y1, z}, {r, y0, z});  // normal −Z
    addRoomCamera(scene);
    return scene;
}

// The form factor from a point facing +Z to the skylight (the square |x|, |z| ≤ 0.5 at y = 2):
// ∫ cos θ₁ cos θ₂ / (π r²) dA by the midpoint rule, 400² cells.
double skylightFormFactor(const vec3& p) {
    const int n = 400;
    const double cell = 1.0 / n;
    double sum = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double dx = -0.5 + (i + 0.5) * cell - p.x, dz = -0.5 + (j + 0.5) * cell - p.z, dy = 2.0 - p.y;
            const double r2 = dx * dx + dy * dy + dz * dz;
            if (dz > 0.0) sum += dz * dy / (r2 * r2) * cell * cell;
        }
    return sum / 3.14159265358979;
}

}  // namespace

TEST_CASE("A panel wound facing its wall: inside holds the side the room sees, lit through the skylight", "[bake]") {
    // The room side sees the sky only through the skylight: its texels hold L × the form
    // factor. The side against the plaster sees the black wall 5 mm off, and light
    // only through the crack round the panel's edge. Neither side sees more than a few of the
    // sky's rays, so only the wall a centimetre away tells the sides apart. Compared over the
    // middle 8 × 8 texels (a record's fan sees the skylight through some 7 of its 100 rays, so
    // one record is noisy), each against the form factor at its own centre (the panel's
    // TEXCOORD_1: u up from y = 0.7, v across from x = 0.3 to −0.3, 0.6 m each).
    double centre = 0.0;
    for (int ty = 12; ty < 20; ++ty)
        for (int tx = 12; tx < 20; ++tx) {
            const float u = (float(tx) + 0.5f) / 32.0f, v = (float(ty) + 0.5f) / 32.0f;
            centre += skylightFormFactor(vec3(-0.3f + 0.6f * (1.0f - v), 0.7f + 0.6f * u, -0.995f)) / 64.0;
        }
    const Scene scene = panelAgainstAWall();
    for (LightmapSide side : {LightmapSide::Front, LightmapSide::Inside}) {
        const BakedLightmap lightmap = meshLightmapUnderSky(scene, side, "panel");
        double mean = 0.0;
        for (int ty = 12; ty < 20; ++ty)
            for (int tx = 12; tx < 20; ++tx) mean += lightmap.total.at(tx, ty, 1) / 64.0;
        INFO(toString(side) << ": centre " << mean << ", the skylight's form factor " << centre);
        if (side == LightmapSide::Front)
            CHECK(mean < 0.05 * centre);  // the face against the wall
        else
            CHECK(mean == Approx(centre).epsilon(0.05));
    }
}

namespace {

// The same black room with its skylight, but its wall at z = −1 is one double-sided sheet wound
// facing the room (or outward), the outdoors behind it (the sky all round). A black panel hangs 5 mm in front
// of it, from the floor to 1.75 m, as wide as the room but for a centimetre each side: the four
// points each of the sheet's two triangles is probed from (their centroids and halfway to their
// corners, up to 1.67 m) all lie behind it, and the room sees the strip above it.
constexpr float kPanelTop = 1.75f;
Scene wallBehindAPanel(bool woundOutward) {
    Scene scene;
    const int black = addLambert(scene, vec3(0.0f));
    const int sheet = addLambert(scene, vec3(0.0f));
    scene.materials[size_t(sheet)].doubleSided = true;
    const float s = 1.0f, h = 2.0f;
    const vec3 p000(-s, 0, -s), p100(s, 0, -s), p010(-s, h, -s), p110(s, h, -s);
    const vec3 p001(-s, 0, s), p101(s, 0, s), p011(-s, h, s), p111(s, h, s);
    addQuad(scene, "floor", black, p000, p001, p101, p100);
    addQuad(scene, "wall-x", black, p000, p010, p011, p001);
    addQuad(scene, "wall+x", black, p100, p101, p111, p110);
    addQuad(scene, "wall+z", black, p001, p011, p111, p101);
    // Normal +Z (−Z wound outward); uv v = 1 − y / h either way.
    if (woundOutward) addQuad(scene, "sheet", sheet, p100, p000, p010, p110);
    else addQuad(scene, "sheet", sheet, p000, p100, p110, p010);
    addCeilingRoundSkylight(scene, black);
    const float z = -s + 0.005f, r = s - 0.01f;
    addQuad(scene, "panel", black, {-r, 0.0f, z}, {r, 0.0f, z}, {r, kPanelTop, z}, {-r, kPanelTop, z});  // normal +Z
    addRoomCamera(scene);
    return scene;
}

}  // namespace

TEST_CASE("A wall's strip above a panel hung on it: inside holds the room's side there, the outdoors behind the "
          "panel",
          "[bake]") {
    // Outdoors the sheet faces the whole uniform sky: L = 1 at its texels. The strip's room side
    // sees the sky only through the skylight: L × the form factor, a few hundredths. Behind the
    // panel neither side is seen from the room, and the sheet's outer face is what the outdoors
    // sees. Before each sample was probed, the whole sheet held the outdoors.
    // Wound outward, the sheet's back is what the panel seals and the strip is its back.
    const bool woundOutward = GENERATE(false, true);
    const Scene scene = wallBehindAPanel(woundOutward);
    const BakedLightmap lightmap = meshLightmapUnderSky(scene, LightmapSide::Inside, "sheet");
    const int n = lightmap.total.width;
    REQUIRE(n == 32);
    // Rows whose texel centres lie 5–17 cm under the ceiling, in the strip; columns the middle half.
    double strip = 0.0, formFactor = 0.0, behind = 0.0;
    int stripTexels = 0, behindTexels = 0;
    for (int y = 0; y < n; ++y) {
        const float height = 2.0f * (1.0f - (float(y) + 0.5f) / float(n));
        for (int x = n / 4; x < 3 * n / 4; ++x) {
            const float across = 2.0f * (float(x) + 0.5f) / float(n) - 1.0f;
            if (height > 1.83f && height < 1.95f) {
                strip += lightmap.total.at(x, y, 1);
                formFactor += skylightFormFactor(vec3(across, height, -1.0f));
                ++stripTexels;
            } else if (height < kPanelTop - 0.15f && height > 0.15f) {
                behind += lightmap.total.at(x, y, 1);
                ++behindTexels;
            }
        }
    }
    REQUIRE(stripTexels >= 16);
    strip /= stripTexels;
    formFactor /= stripTexels;
    behind /= behindTexels;
    INFO((woundOutward ? "wound outward: " : "wound facing the room: ") << "strip " << strip << " against the skylight's form factor " << formFactor << ", behind the panel " << behind);
    CHECK(strip == Approx(formFactor).epsilon(0.1));
    CHECK(behind == Approx(1.0).epsilon(0.02));
}

TEST_CASE("lightmap-side takes front and inside and names itself when wrong", "[bake]") {
    CHECK(parseLightmapSide("front") == LightmapSide::Front);
    CHECK(parseLightmapSide("inside") == LightmapSide::Inside);
    CHECK_THROWS_WITH(parseLightmapSide("back"), Catch::Contains("lightmap-side") && Catch::Contains("'back'") &&
                                                     Catch::Contains("front, inside"));
}
