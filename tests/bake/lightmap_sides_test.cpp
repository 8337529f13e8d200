// Which side of a double-sided surface a lightmap holds (bake/lightmap_sides.h): a lid closing a
// black box, its front facing the sky. Under a uniform sky of radiance L its top receives π L
// (texel L) and its underside nothing (the box is closed and black): the setting picks which.
#include "bake/bake.h"
#include "bake/receivers.h"
#include "core/error.h"
#include "quad_scene.h"

#include <catch2/catch.hpp>

using namespace vl;
using namespace vl::test;

namespace {

Scene lidOnABlackBox() {
    Scene scene;
    const int black = addLambert(scene, vec3(0.0f));
    const int lid = addLambert(scene, vec3(0.5f));
    scene.materials[size_t(lid)].doubleSided = true;
    // The box's floor and four walls, facing in; no ceiling: the lid closes it.
    const vec3 lo(-0.5f, 0.0f, -0.5f), hi(0.5f, 0.4f, 0.5f);
    const vec3 p000(lo.x, lo.y, lo.z), p100(hi.x, lo.y, lo.z), p010(lo.x, hi.y, lo.z), p110(hi.x, hi.y, lo.z);
    const vec3 p001(lo.x, lo.y, hi.z), p101(hi.x, lo.y, hi.z), p011(lo.x, hi.y, hi.z), p111(hi.x, hi.y, hi.z);
    addQuad(scene, "floor", black, p000, p001, p101, p100);
    addQuad(scene, "wall-x", black, p000, p010, p011, p001);
    addQuad(scene, "wall+x", black, p100, p101, p111, p110);
    addQuad(scene, "wall-z", black, p000, p100, p110, p010);
    addQuad(scene, "wall+z", black, p001, p011, p111, p101);
    addQuad(scene, "lid", lid, p010, p011, p111, p110);  // normal +Y: its front faces the sky
    return scene;
}

// The lid's lightmap: its covered texels' mean and extremes (green).
struct LidTexels {
    double mean = 0.0, lowest = 1e30, highest = -1e30;
    size_t count = 0;
};

LidTexels lidTexels(LightmapSide side) {
    const Scene scene = lidOnABlackBox();
    BakeSettings settings = quietSettings();
    settings.sky = vec3(1.0f);
    settings.lightmap.atlasPerMesh = true;
    settings.lightmap.width = settings.lightmap.height = 32;
    settings.lightmapSide = side;
    Diagnostics diagnostics(false, false);
    const BakeResult result = bake(scene, settings, diagnostics);
    LidTexels lid;
    for (const BakedLightmap& lightmap : result.lightmaps) {
        if (lightmap.name.find("lid") == std::string::npos) continue;
        for (int y = 0; y < lightmap.mask.height; ++y)
            for (int x = 0; x < lightmap.mask.width; ++x) {
                if (lightmap.mask.at(x, y) < 0.5f) continue;
                const double v = lightmap.total.at(x, y, 1);
                lid.mean += v;
                lid.lowest = std::min(lid.lowest, v);
                lid.highest = std::max(lid.highest, v);
                ++lid.count;
            }
    }
    if (lid.count) lid.mean /= double(lid.count);
    return lid;
}

}  // namespace

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

TEST_CASE("lightmap-side takes front and inside and names itself when wrong", "[bake]") {
    CHECK(parseLightmapSide("front") == LightmapSide::Front);
    CHECK(parseLightmapSide("inside") == LightmapSide::Inside);
    CHECK_THROWS_WITH(parseLightmapSide("back"), Catch::Contains("lightmap-side") && Catch::Contains("'back'") &&
                                                     Catch::Contains("front, inside"));
}
