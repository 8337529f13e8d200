// Generates the project's own scenes into scenes/: the standard Cornell box from the
// published Cornell measurements (https://www.graphics.cornell.edu/online/box/data.html),
// lit by its 130 × 105 mm ceiling light as an emissive quad, and a variant lit by one
// point light; and two sealed rooms sharing a thin wall, one lit, for light leaks. Run
// `build/make_scenes scenes` after editing; the outputs are committed.
//
// The published data is in millimetres with the camera looking along +Z; glTF cameras look
// along −Z, so the box is mapped by (x, y, z) ↦ (0.556 − x, y, −z)/1000, the same mapping as
// the Blender-exported references in ../shared/reference.
#include "scenes/gltf_writer.h"

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>

using namespace vl;
using namespace vl::scenes;

namespace {

vec3 fromCornell(float x, float y, float z) { return vec3(0.556f - x / 1000.0f, y / 1000.0f, -z / 1000.0f); }

Quad cornellQuad(const float (&p)[12]) {
    return {fromCornell(p[0], p[1], p[2]), fromCornell(p[3], p[4], p[5]), fromCornell(p[6], p[7], p[8]),
            fromCornell(p[9], p[10], p[11])};
}

// Reverses a quad whose normal does not point the way `facing` says (towards `target`
// when inward, away from it otherwise): the published lists do not share one winding.
Quad oriented(Quad q, const vec3& target, bool inward) {
    const vec3 n = glm::cross(q[1] - q[0], q[3] - q[0]);
    const vec3 centre = 0.25f * (q[0] + q[1] + q[2] + q[3]);
    const bool pointsToTarget = glm::dot(n, target - centre) > 0.0f;
    if (pointsToTarget != inward) std::swap(q[1], q[3]);
    return q;
}

SceneMesh block(const char* name, const float (&faces)[5][12]) {
    SceneMesh mesh{name, 0, {}, true};
    vec3 centroid(0.0f);
    for (const auto& f : faces) {
        const Quad q = cornellQuad(f);
        centroid += 0.25f * (q[0] + q[1] + q[2] + q[3]) / 5.0f;
    }
    centroid.y = 0.5f * centroid.y;  // the open bottom biases the face average upwards
    for (const auto& f : faces) mesh.quads.push_back(oriented(cornellQuad(f), centroid, false));
    return mesh;
}

SceneDescription cornellBox(bool pointLight) {
    SceneDescription scene;
    scene.materials = {{"White", vec3(0.73f), vec3(0.0f), 1.0f},
                       {"Red", vec3(0.63f, 0.065f, 0.05f), vec3(0.0f), 1.0f},
                       {"Green", vec3(0.14f, 0.45f, 0.091f), vec3(0.0f), 1.0f},
                       {"Light", vec3(0.0f), vec3(1.0f), 17.0f}};
    const vec3 inside = fromCornell(278.0f, 274.4f, 279.6f);
    auto wall = [&](const char* name, int material, const float (&p)[12]) {
        return SceneMesh{name, material, {oriented(cornellQuad(p), inside, true)}, true};
    };
    scene.meshes.push_back(wall("Floor", 0, {552.8f, 0, 0, 0, 0, 0, 0, 0, 559.2f, 549.6f, 0, 559.2f}));
    scene.meshes.push_back(wall("BackWall", 0, {549.6f, 0, 559.2f, 0, 0, 559.2f, 0, 548.8f, 559.2f, 556.0f, 548.8f, 559.2f}));
    scene.meshes.push_back(wall("RedWall", 1, {552.8f, 0, 0, 549.6f, 0, 559.2f, 556.0f, 548.8f, 559.2f, 556.0f, 548.8f, 0}));
    scene.meshes.push_back(wall("GreenWall", 2, {0, 0, 559.2f, 0, 0, 0, 0, 548.8f, 0, 0, 548.8f, 559.2f}));

    SceneMesh ceiling{"Ceiling", 0, {}, true};
    const float y = 548.8f;
    auto ceilingPiece = [&](float x0, float z0, float x1, float z1) {
        ceiling.quads.push_back(oriented(cornellQuad({x0, y, z0, x1, y, z0, x1, y, z1, x0, y, z1}), inside, true));
    };
    if (pointLight) {
        ceilingPiece(0.0f, 0.0f, 556.0f, 559.2f);
    } else {
        // The ceiling with a hole the light quad closes flush.
        ceilingPiece(0.0f, 0.0f, 556.0f, 227.0f);
        ceilingPiece(0.0f, 332.0f, 556.0f, 559.2f);
        ceilingPiece(0.0f, 227.0f, 213.0f, 332.0f);
        ceilingPiece(343.0f, 227.0f, 556.0f, 332.0f);
    }
    scene.meshes.push_back(ceiling);

    if (pointLight) {
        // Blender's 2 W point light: I = 2/(4π) W/sr, glTF intensity I × 683 cd.
        scene.lights.push_back({"PointLight", vec3(0.278f, 0.5f, -0.2795f), vec3(1.0f),
                                2.0f / (4.0f * kPi) * 683.0f});
    } else {
        SceneMesh light{"Light", 3, {oriented(cornellQuad({343.0f, y, 227.0f, 343.0f, y, 332.0f, 213.0f, y, 332.0f,
                                                           213.0f, y, 227.0f}),
                                              inside, true)},
                        false};
        scene.meshes.push_back(light);
    }

    const float shortBlock[5][12] = {
        {130.0f, 165.0f, 65.0f, 82.0f, 165.0f, 225.0f, 240.0f, 165.0f, 272.0f, 290.0f, 165.0f, 114.0f},
        {290.0f, 0.0f, 114.0f, 290.0f, 165.0f, 114.0f, 240.0f, 165.0f, 272.0f, 240.0f, 0.0f, 272.0f},
        {130.0f, 0.0f, 65.0f, 130.0f, 165.0f, 65.0f, 290.0f, 165.0f, 114.0f, 290.0f, 0.0f, 114.0f},
        {82.0f, 0.0f, 225.0f, 82.0f, 165.0f, 225.0f, 130.0f, 165.0f, 65.0f, 130.0f, 0.0f, 65.0f},
        {240.0f, 0.0f, 272.0f, 240.0f, 165.0f, 272.0f, 82.0f, 165.0f, 225.0f, 82.0f, 0.0f, 225.0f}};
    const float tallBlock[5][12] = {
        {423.0f, 330.0f, 247.0f, 265.0f, 330.0f, 296.0f, 314.0f, 330.0f, 456.0f, 472.0f, 330.0f, 406.0f},
        {423.0f, 0.0f, 247.0f, 423.0f, 330.0f, 247.0f, 472.0f, 330.0f, 406.0f, 472.0f, 0.0f, 406.0f},
        {472.0f, 0.0f, 406.0f, 472.0f, 330.0f, 406.0f, 314.0f, 330.0f, 456.0f, 314.0f, 0.0f, 456.0f},
        {314.0f, 0.0f, 456.0f, 314.0f, 330.0f, 456.0f, 265.0f, 330.0f, 296.0f, 265.0f, 0.0f, 296.0f},
        {265.0f, 0.0f, 296.0f, 265.0f, 330.0f, 296.0f, 423.0f, 330.0f, 247.0f, 423.0f, 0.0f, 247.0f}};
    scene.meshes.push_back(block("ShortBlock", shortBlock));
    scene.meshes.push_back(block("TallBlock", tallBlock));

    // The published pinhole: 35 mm focal length, 25 mm film, 800 mm in front of the box.
    scene.camera.position = vec3(0.278f, 0.273f, 0.8f);
    scene.camera.yfov = 2.0f * std::atan(12.5f / 35.0f);
    scene.camera.aspectRatio = 1.0f;
    return scene;
}

// Two sealed rooms of white walls (albedo 0.8) side by side along x, 3 × 2.5 × 3 m inside,
// sharing one wall kTwoRoomsWall thick, a 40 W point light in room A and none in room B:
// the truth in room B is black, and with walls this bright indirect light is three times the
// direct, so any light the voxels carry through the wall shows (issue 13's leak scene).
constexpr float kTwoRoomsWall = 0.1f;

SceneDescription twoRooms() {
    SceneDescription scene;
    scene.materials = {{"Plaster", vec3(0.8f), vec3(0.0f), 1.0f}};
    auto room = [&](const std::string& prefix, vec3 lo, vec3 hi) {
        const vec3 inside = 0.5f * (lo + hi);
        auto face = [&](const char* name, vec3 a, vec3 b, vec3 c, vec3 d) {
            scene.meshes.push_back({prefix + name, 0, {oriented({a, b, c, d}, inside, true)}, true});
        };
        face("Floor", {lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, lo.y, hi.z}, {lo.x, lo.y, hi.z});
        face("Ceiling", {lo.x, hi.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z});
        face("WallMinusX", {lo.x, lo.y, lo.z}, {lo.x, hi.y, lo.z}, {lo.x, hi.y, hi.z}, {lo.x, lo.y, hi.z});
        face("WallPlusX", {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {hi.x, lo.y, hi.z});
        face("WallMinusZ", {lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z});
        face("WallPlusZ", {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z});
    };
    room("A", vec3(0.0f), vec3(3.0f, 2.5f, 3.0f));
    room("B", vec3(3.0f + kTwoRoomsWall, 0.0f, 0.0f), vec3(6.0f + kTwoRoomsWall, 2.5f, 3.0f));
    scene.lights.push_back({"Lamp", vec3(1.2f, 1.9f, 1.7f), vec3(1.0f), 40.0f / (4.0f * kPi) * 683.0f});
    // In room A's corner, looking across it at the shared wall.
    scene.camera.position = vec3(0.3f, 1.6f, 2.7f);
    scene.camera.yfov = 1.2f;
    scene.camera.aspectRatio = 1.0f;
    return scene;
}

}  // namespace

int main(int argc, char** argv) {
    const std::string directory = argc > 1 ? argv[1] : "scenes";
    try {
        std::filesystem::create_directories(directory);
        writeGltf(cornellBox(false), directory, "cornell_box");
        writeGltf(cornellBox(true), directory, "cornell_box_point");
        writeGltf(twoRooms(), directory, "two_rooms");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "make_scenes: %s\n", e.what());
        return 1;
    }
    std::printf("wrote cornell_box.gltf, cornell_box_point.gltf and two_rooms.gltf into %s\n", directory.c_str());
    return 0;
}
