// A scene's own frame (scene/own_frame.h) and turning a scene into it (Scene::turnFrame): the
// axes found for a room turned by a known rotation, the identity where there is nothing to
// turn, and a turn that leaves every point where it was in the world.
#include "scene/own_frame.h"
#include "scene/scene.h"

#include <catch2/catch.hpp>
#include <glm/gtc/matrix_transform.hpp>

using namespace vl;

namespace {

// A closed box [0, size] of six inward quads, two triangles each, turned by `turn`.
Scene turnedRoom(vec3 size, const glm::mat3& turn) {
    Scene scene;
    Mesh mesh;
    mesh.name = "room";
    const vec3 lo(0.0f), hi = size;
    const auto quad = [&](vec3 a, vec3 b, vec3 c, vec3 d) {
        const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
        for (const vec3& p : {a, b, c, d}) mesh.positions.push_back(turn * p);
        const vec3 n = glm::normalize(glm::cross(turn * b - turn * a, turn * d - turn * a));
        for (int k = 0; k < 4; ++k) mesh.normals.push_back(n);
        for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) mesh.indices.push_back(base + i);
    };
    const vec3 p000(lo.x, lo.y, lo.z), p100(hi.x, lo.y, lo.z), p010(lo.x, hi.y, lo.z), p110(hi.x, hi.y, lo.z);
    const vec3 p001(lo.x, lo.y, hi.z), p101(hi.x, lo.y, hi.z), p011(lo.x, hi.y, hi.z), p111(hi.x, hi.y, hi.z);
    quad(p000, p001, p101, p100);
    quad(p010, p110, p111, p011);
    quad(p000, p010, p011, p001);
    quad(p100, p101, p111, p110);
    quad(p000, p100, p110, p010);
    quad(p001, p011, p111, p101);
    scene.meshes.push_back(mesh);
    Light light;
    light.position = turn * (0.5f * size);
    light.direction = turn * vec3(0.0f, -1.0f, 0.0f);
    scene.lights.push_back(light);
    return scene;
}

glm::mat3 rotation(float radians, vec3 axis) {
    return glm::mat3(glm::rotate(glm::mat4(1.0f), radians, glm::normalize(axis)));
}

}  // namespace

TEST_CASE("A turned room's own axes are its walls' normals, and turning into them squares it up", "[scene]") {
    const glm::mat3 turn = rotation(0.7f, vec3(1.0f, 2.0f, 0.5f));
    Scene scene = turnedRoom(vec3(3.0f, 2.0f, 1.0f), turn);
    const glm::dmat3 axes = ownFrameAxes(scene);
    // Each own axis is one of the turned room's axes (up to sign), and the axes are a rotation.
    for (int k = 0; k < 3; ++k) {
        double best = 0.0;
        for (int a = 0; a < 3; ++a) best = std::max(best, std::abs(glm::dot(axes[k], glm::dvec3(turn[a]))));
        CHECK(best == Approx(1.0).epsilon(1e-6));
    }
    CHECK(glm::determinant(axes) == Approx(1.0).epsilon(1e-9));

    const std::vector<vec3> before = scene.meshes[0].positions;
    REQUIRE(turnToOwnFrame(scene));
    // Squared up: every vertex's coordinates take two values per axis, the room's extent
    // (3 × 2 × 1 in some order of axes).
    const Aabb box = scene.bounds();
    vec3 extent = box.extent();
    std::sort(&extent.x, &extent.x + 3);
    CHECK(extent.x == Approx(1.0f).epsilon(1e-5));
    CHECK(extent.y == Approx(2.0f).epsilon(1e-5));
    CHECK(extent.z == Approx(3.0f).epsilon(1e-5));
    for (const vec3& p : scene.meshes[0].positions)
        for (int a = 0; a < 3; ++a)
            CHECK(std::min(std::abs(p[a] - box.lower[a]), std::abs(p[a] - box.upper[a])) <= 1e-5f);
    // In place in the world: origin + frame · local is where the vertex was.
    for (size_t v = 0; v < before.size(); ++v) {
        const glm::dvec3 world = scene.origin + scene.frame * glm::dvec3(scene.meshes[0].positions[v]);
        CHECK(glm::distance(world, glm::dvec3(before[v])) <= 1e-5);
    }
    // Directions turn with it: the light still points along the room's turned −Y.
    CHECK(glm::distance(scene.frame * glm::dvec3(scene.lights[0].direction), glm::dvec3(turn * vec3(0, -1, 0))) <= 1e-5);
    // Turned once, it is in its own frame.
    CHECK(ownFrameAxes(scene) == glm::dmat3(1.0));
    CHECK_FALSE(turnToOwnFrame(scene));
}

TEST_CASE("Moving a turned scene's origin keeps every point where it is in the world", "[scene]") {
    Scene scene = turnedRoom(vec3(3.0f, 2.0f, 1.0f), rotation(0.7f, vec3(1.0f, 2.0f, 0.5f)));
    scene.origin = glm::dvec3(1000.0, -20.0, 5.0);
    REQUIRE(turnToOwnFrame(scene));
    const auto world = [&](const vec3& p) { return scene.origin + scene.frame * glm::dvec3(p); };
    std::vector<glm::dvec3> before;
    for (const vec3& p : scene.meshes[0].positions) before.push_back(world(p));
    const glm::dvec3 lightBefore = world(scene.lights[0].position);
    scene.moveOrigin(glm::dvec3(1001.5, -19.0, 7.25));
    for (size_t v = 0; v < before.size(); ++v) CHECK(glm::distance(world(scene.meshes[0].positions[v]), before[v]) <= 1e-5);
    CHECK(glm::distance(world(scene.lights[0].position), lightBefore) <= 1e-5);
}

TEST_CASE("A scene with nothing to turn keeps its frame exactly", "[scene]") {
    SECTION("axis-aligned") {
        CHECK(ownFrameAxes(turnedRoom(vec3(3.0f, 2.0f, 1.0f), glm::mat3(1.0f))) == glm::dmat3(1.0));
    }
    SECTION("a quarter turn") {
        const glm::mat3 quarter(vec3(0.0f, 0.0f, -1.0f), vec3(0.0f, 1.0f, 0.0f), vec3(1.0f, 0.0f, 0.0f));
        CHECK(ownFrameAxes(turnedRoom(vec3(3.0f, 2.0f, 1.0f), quarter)) == glm::dmat3(1.0));
    }
    SECTION("turned by less than kOwnFrameMinTurn") {
        CHECK(ownFrameAxes(turnedRoom(vec3(3.0f, 2.0f, 1.0f), rotation(0.8f * float(kOwnFrameMinTurn), vec3(1, 1, 0)))) ==
              glm::dmat3(1.0));
        CHECK(ownFrameAxes(turnedRoom(vec3(3.0f, 2.0f, 1.0f), rotation(1.5f * float(kOwnFrameMinTurn), vec3(1, 1, 0)))) !=
              glm::dmat3(1.0));
    }
    SECTION("a single plane") {
        Scene plane = turnedRoom(vec3(1.0f), rotation(0.4f, vec3(1, 0, 0)));
        plane.meshes[0].indices.resize(6);  // the floor alone
        CHECK(ownFrameAxes(plane) == glm::dmat3(1.0));
    }
}
