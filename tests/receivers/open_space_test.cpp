// The open space people stand in (receivers/open_space.h): a closed box seals its inside from a
// viewpoint outside it and the outside from one within, whichever way its faces are wound; a
// window joins the two.
#include "receivers/open_space.h"
#include "support/room_scenes.h"
#include "trace/bvh.h"

#include <catch2/catch.hpp>

using namespace vl;
using namespace vl::test;

namespace {

// A box [0, 2]³ inside a ground quad 6 m wide at y = −1 (so the grid reaches well outside the
// box), its faces wound inward or outward; `window` cuts a 0.6 m hole in the +X wall.
Scene boxScene(bool woundOutward, bool window) {
    Scene scene;
    const int grey = addLambert(scene, vec3(0.5f));
    addQuad(scene, "ground", grey, {-2, -1, -2}, {-2, -1, 4}, {4, -1, 4}, {4, -1, -2});
    addRoom(scene, "box-", grey, vec3(0.0f), vec3(2.0f));
    if (window) {
        // The +X wall again as four quads round a hole from (y, z) 0.7 to 1.3.
        scene.meshes.erase(std::find_if(scene.meshes.begin(), scene.meshes.end(),
                                        [](const Mesh& m) { return m.name == "box-wall+x"; }));
        const float x = 2.0f, a = 0.7f, b = 1.3f;
        addQuad(scene, "sill", grey, {x, 0, 0}, {x, 0, 2}, {x, a, 2}, {x, a, 0});
        addQuad(scene, "head", grey, {x, b, 0}, {x, b, 2}, {x, 2, 2}, {x, 2, 0});
        addQuad(scene, "jamb-", grey, {x, a, 0}, {x, a, a}, {x, b, a}, {x, b, 0});
        addQuad(scene, "jamb+", grey, {x, a, b}, {x, a, 2}, {x, b, 2}, {x, b, b});
    }
    if (woundOutward)
        for (Mesh& mesh : scene.meshes)
            if (mesh.name != "ground") std::reverse(mesh.indices.begin(), mesh.indices.end());
    return scene;
}

struct Probe {
    bool inside, outside;
};

Probe probe(const Scene& scene, vec3 viewpoint) {
    const SceneTriangles triangles = gatherTriangles(scene);
    const TraceScene trace = TraceScene::build(scene, triangles);
    const OpenSpace space(trace.view(), {{viewpoint, vec3(0.0f, 0.0f, -1.0f)}});
    REQUIRE(!space.empty());
    return {space.open(vec3(1.0f, 1.5f, 0.5f)), space.open(vec3(3.0f, 0.5f, 3.0f))};
}

}  // namespace

TEST_CASE("Open space: a closed box seals its inside from the outside, either winding", "[bake]") {
    for (bool outward : {false, true}) {
        INFO("wound " << (outward ? "outward" : "inward"));
        const Scene scene = boxScene(outward, false);
        const Probe fromInside = probe(scene, vec3(1.0f));
        CHECK(fromInside.inside);
        CHECK_FALSE(fromInside.outside);
        const Probe fromOutside = probe(scene, vec3(3.5f, 0.0f, -1.5f));
        CHECK_FALSE(fromOutside.inside);
        CHECK(fromOutside.outside);
        // A viewpoint beyond the scene's bounds stands in the air round it.
        const Probe fromAfar = probe(scene, vec3(20.0f, 0.0f, 0.0f));
        CHECK_FALSE(fromAfar.inside);
        CHECK(fromAfar.outside);
    }
}

TEST_CASE("Open space: a window joins a box's inside to the outside", "[bake]") {
    const Probe fromInside = probe(boxScene(false, true), vec3(1.0f));
    CHECK(fromInside.inside);
    CHECK(fromInside.outside);
}

TEST_CASE("Open space: nothing is open without a viewpoint, nor from one inside a wall", "[bake]") {
    const Scene scene = boxScene(false, false);
    const SceneTriangles triangles = gatherTriangles(scene);
    const TraceScene trace = TraceScene::build(scene, triangles);
    CHECK(OpenSpace(trace.view(), {}).empty());
    const OpenSpace inWall(trace.view(), {{vec3(2.0f, 1.0f, 1.0f), vec3(0.0f, 0.0f, -1.0f)}});
    CHECK_FALSE(inWall.open(vec3(1.0f)));
    CHECK_FALSE(inWall.open(vec3(3.0f, 0.5f, 3.0f)));
}
