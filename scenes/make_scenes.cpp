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

#include "core/image.h"
#include "core/image_io.h"

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>

using namespace vl;
using namespace vl::scenes;

namespace {

SceneMaterial material(std::string name, vec3 baseColor, vec3 emissiveFactor = vec3(0.0f), float emissiveStrength = 1.0f,
                       std::string texture = "", float textureMetres = 0.0f) {
    SceneMaterial m;
    m.name = std::move(name);
    m.baseColor = baseColor;
    m.emissiveFactor = emissiveFactor;
    m.emissiveStrength = emissiveStrength;
    m.baseColorTexture = std::move(texture);
    m.textureMetres = textureMetres;
    return m;
}

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
    scene.materials = {material("White", vec3(0.73f), vec3(0.0f), 1.0f),
                       material("Red", vec3(0.63f, 0.065f, 0.05f), vec3(0.0f), 1.0f),
                       material("Green", vec3(0.14f, 0.45f, 0.091f), vec3(0.0f), 1.0f),
                       material("Light", vec3(0.0f), vec3(1.0f), 17.0f)};
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
    scene.materials = {material("Plaster", vec3(0.8f), vec3(0.0f), 1.0f)};
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

// A box [lo, hi] as six outward quads.
std::vector<Quad> boxQuads(vec3 lo, vec3 hi) {
    const vec3 c = 0.5f * (lo + hi);
    const vec3 p000(lo.x, lo.y, lo.z), p100(hi.x, lo.y, lo.z), p010(lo.x, hi.y, lo.z), p110(hi.x, hi.y, lo.z);
    const vec3 p001(lo.x, lo.y, hi.z), p101(hi.x, lo.y, hi.z), p011(lo.x, hi.y, hi.z), p111(hi.x, hi.y, hi.z);
    return {oriented({p000, p100, p101, p001}, c, false), oriented({p010, p110, p111, p011}, c, false),
            oriented({p000, p010, p011, p001}, c, false), oriented({p100, p110, p111, p101}, c, false),
            oriented({p000, p100, p110, p010}, c, false), oriented({p001, p101, p111, p011}, c, false)};
}

// Deterministic texture noise in [0, 1).
float hashNoise(uint32_t x, uint32_t y, uint32_t salt) {
    uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ salt * 0xcb1ab31fu;
    h ^= h >> 13;
    h *= 0x5bd1e995u;
    h ^= h >> 15;
    return static_cast<float>(h & 0xFFFFFFu) / 16777216.0f;
}

// Oak planks, 8 across the texture, each its own shade, with grain and dark seams (linear
// albedo; written as an sRGB PNG).
Image plankTexture() {
    const int size = 256, planks = 8, width = size / planks;
    Image image(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const int plank = x / width;
            const int offset = static_cast<int>(hashNoise(uint32_t(plank), 0, 7) * size);
            const float shade = 0.8f + 0.4f * hashNoise(uint32_t(plank), uint32_t((y + offset) / size), 3);
            const float grain = 0.9f + 0.1f * std::sin(0.35f * float(y + offset) + 3.0f * hashNoise(uint32_t(x), 0, 5));
            const bool seam = x % width == 0 || (y + offset) % size == 0;
            const float k = shade * grain * (seam ? 0.45f : 1.0f);
            image.setRgb(x, y, vec3(0.42f, 0.27f, 0.15f) * k);
        }
    return image;
}

// A green chalkboard with a few lines of chalk writing and a worn, cloudy surface.
Image boardTexture() {
    const int w = 512, h = 128;
    Image image(w, h, 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float cloud = 0.85f + 0.3f * hashNoise(uint32_t(x / 16), uint32_t(y / 16), 11);
            vec3 colour = vec3(0.035f, 0.10f, 0.06f) * cloud;
            const int line = (y - 18) / 22;
            const int inLine = (y - 18) % 22;
            const int lineLength = 180 + static_cast<int>(hashNoise(uint32_t(line), 0, 13) * 250);
            if (y >= 18 && line < 4 && inLine < 9 && x > 24 && x < 24 + lineLength) {
                const int letter = (x - 24) / 9;
                const bool space = hashNoise(uint32_t(letter), uint32_t(line), 17) < 0.18f;
                const bool stroke = hashNoise(uint32_t(x), uint32_t(y), 19) < 0.55f;
                if (!space && stroke && (x - 24) % 9 < 6) colour = vec3(0.55f, 0.57f, 0.52f);
            }
            image.setRgb(x, y, colour);
        }
    return image;
}

// A classroom for the VR/AR language classes the project's paper is about: 10 × 8 × 3.2 m,
// five rows of four desks with chairs facing the board, a teacher's desk, a door, three
// windows in the +X wall open to the sky and the sun (both from its job file,
// scenes/classroom.json: glTF has no sky), and six ceiling lamp panels. Plank-textured floor
// and a chalkboard texture; no TEXCOORD_1: the bake generates the lightmap's charts.
SceneDescription classroom() {
    SceneDescription scene;
    enum { kPlaster, kCeiling, kFloor, kBoard, kWood, kChair, kFrame, kDoor, kLamp };
    scene.materials = {material("Plaster", vec3(0.72f, 0.70f, 0.64f)),
                       material("Ceiling", vec3(0.82f)),
                       material("Floor", vec3(1.0f), vec3(0.0f), 1.0f, "classroom_floor.png", 1.2f),
                       material("Board", vec3(1.0f), vec3(0.0f), 1.0f, "classroom_board.png", 0.0f),
                       material("DeskWood", vec3(0.55f, 0.40f, 0.25f)),
                       material("ChairPlastic", vec3(0.12f, 0.22f, 0.42f)),
                       material("Frame", vec3(0.25f)),
                       material("Door", vec3(0.33f, 0.20f, 0.11f)),
                       material("Lamp", vec3(0.9f), vec3(1.0f, 0.96f, 0.88f), 6.0f)};
    const float X = 10.0f, Y = 3.2f, Z = -8.0f;
    const vec3 inside(5.0f, 1.6f, -4.0f);
    auto face = [&](std::vector<Quad>& quads, vec3 a, vec3 b, vec3 c, vec3 d) { quads.push_back(oriented({a, b, c, d}, inside, true)); };
    auto mesh = [&](const std::string& name, int material, std::vector<Quad> quads) {
        scene.meshes.push_back({name, material, std::move(quads), false});
    };
    std::vector<Quad> floor, ceiling, walls;
    face(floor, {0, 0, 0}, {X, 0, 0}, {X, 0, Z}, {0, 0, Z});
    face(ceiling, {0, Y, 0}, {X, Y, 0}, {X, Y, Z}, {0, Y, Z});
    face(walls, {0, 0, 0}, {X, 0, 0}, {X, Y, 0}, {0, Y, 0});  // back
    face(walls, {0, 0, Z}, {X, 0, Z}, {X, Y, Z}, {0, Y, Z});  // front, the board's
    face(walls, {0, 0, 0}, {0, 0, Z}, {0, Y, Z}, {0, Y, 0});  // −X, the door's
    // +X: three windows 1.6 m wide from 0.9 m to 2.6 m, centred at z = −1.6, −4.0, −6.4.
    const float sill = 0.9f, head = 2.6f;
    face(walls, {X, 0, 0}, {X, 0, Z}, {X, sill, Z}, {X, sill, 0});
    face(walls, {X, head, 0}, {X, head, Z}, {X, Y, Z}, {X, Y, 0});
    const float piers[4][2] = {{0.0f, -0.8f}, {-2.4f, -3.2f}, {-4.8f, -5.6f}, {-7.2f, Z}};
    for (const auto& p : piers) face(walls, {X, sill, p[0]}, {X, sill, p[1]}, {X, head, p[1]}, {X, head, p[0]});
    mesh("Floor", kFloor, floor);
    mesh("Ceiling", kCeiling, ceiling);
    mesh("Walls", kPlaster, walls);
    std::vector<Quad> board, door;
    face(board, {2.5f, 0.9f, Z + 0.01f}, {7.5f, 0.9f, Z + 0.01f}, {7.5f, 2.1f, Z + 0.01f}, {2.5f, 2.1f, Z + 0.01f});
    face(door, {0.01f, 0.0f, -0.8f}, {0.01f, 0.0f, -1.8f}, {0.01f, 2.1f, -1.8f}, {0.01f, 2.1f, -0.8f});
    mesh("Board", kBoard, board);
    mesh("Door", kDoor, door);

    // Lamp panels 1.2 × 0.6 m, 1 cm under the ceiling, facing down.
    std::vector<Quad> lamps;
    for (float x : {3.0f, 7.0f})
        for (float z : {-1.8f, -4.2f, -6.6f}) {
            const float y = Y - 0.01f;
            lamps.push_back(oriented({vec3(x - 0.6f, y, z - 0.3f), vec3(x + 0.6f, y, z - 0.3f), vec3(x + 0.6f, y, z + 0.3f),
                                      vec3(x - 0.6f, y, z + 0.3f)},
                                     vec3(x, 0.0f, z), true));
        }
    mesh("LampPanels", kLamp, lamps);

    // Desks (top and two side panels) and chairs (seat, back, two side panels): five rows
    // of four, the students facing −Z.
    std::vector<Quad> desks, frames, chairs;
    auto add = [](std::vector<Quad>& to, const std::vector<Quad>& quads) { to.insert(to.end(), quads.begin(), quads.end()); };
    for (int row = 0; row < 5; ++row)
        for (int column = 0; column < 4; ++column) {
            const float x = 1.6f + 2.25f * float(column), z = -5.6f + 1.05f * float(row);
            add(desks, boxQuads({x - 0.6f, 0.72f, z - 0.3f}, {x + 0.6f, 0.76f, z + 0.3f}));
            add(frames, boxQuads({x - 0.58f, 0.0f, z - 0.25f}, {x - 0.55f, 0.72f, z + 0.25f}));
            add(frames, boxQuads({x + 0.55f, 0.0f, z - 0.25f}, {x + 0.58f, 0.72f, z + 0.25f}));
            const float cz = z + 0.55f;
            add(chairs, boxQuads({x - 0.21f, 0.43f, cz - 0.21f}, {x + 0.21f, 0.47f, cz + 0.21f}));
            add(chairs, boxQuads({x - 0.21f, 0.47f, cz + 0.19f}, {x + 0.21f, 0.88f, cz + 0.22f}));
            add(frames, boxQuads({x - 0.22f, 0.0f, cz - 0.2f}, {x - 0.2f, 0.43f, cz + 0.2f}));
            add(frames, boxQuads({x + 0.2f, 0.0f, cz - 0.2f}, {x + 0.22f, 0.43f, cz + 0.2f}));
        }
    add(desks, boxQuads({4.0f, 0.0f, -7.2f}, {6.0f, 0.76f, -6.4f}));  // the teacher's
    mesh("Desks", kWood, desks);
    mesh("Chairs", kChair, chairs);
    mesh("Frames", kFrame, frames);

    // From the back of the room, left of the middle, over the last row toward the board,
    // the windows and their sun on the right.
    scene.camera.position = vec3(3.6f, 1.8f, -0.2f);
    scene.camera.yfov = 1.0f;
    scene.camera.aspectRatio = 1.5f;
    return scene;
}

// A hall of many lights (issue 35's many-emitter scene): 12 × 8 × 24 m, its two long walls
// each holding ten windows of 10 × 10 emissive panes (2,000 quads a centimetre off the wall,
// facing in, the wall showing between them as mullions), and 200 point lights hung in a
// 10 × 20 grid at 3.2 m. Two rows of pillars and a row of tables cast the shadows that make
// the lights' visibility matter. Every receiver sees hundreds of lights, most of them far.
SceneDescription manyLightsHall() {
    SceneDescription scene;
    enum { kWall, kCeiling, kFloor, kStone, kWood, kPane };
    scene.materials = {material("Wall", vec3(0.70f, 0.68f, 0.62f)),
                       material("Ceiling", vec3(0.75f)),
                       material("Floor", vec3(0.45f, 0.42f, 0.38f)),
                       material("Stone", vec3(0.55f, 0.55f, 0.58f)),
                       material("TableWood", vec3(0.50f, 0.34f, 0.20f)),
                       material("Pane", vec3(0.0f), vec3(0.85f, 0.92f, 1.0f), 3.0f)};
    const float X = 12.0f, Y = 8.0f, Z = -24.0f;
    const vec3 inside(0.5f * X, 0.5f * Y, 0.5f * Z);
    auto face = [&](std::vector<Quad>& quads, vec3 a, vec3 b, vec3 c, vec3 d) { quads.push_back(oriented({a, b, c, d}, inside, true)); };
    auto mesh = [&](const std::string& name, int material, std::vector<Quad> quads) {
        scene.meshes.push_back({name, material, std::move(quads), false});
    };
    std::vector<Quad> floor, ceiling, walls;
    face(floor, {0, 0, 0}, {X, 0, 0}, {X, 0, Z}, {0, 0, Z});
    face(ceiling, {0, Y, 0}, {X, Y, 0}, {X, Y, Z}, {0, Y, Z});
    face(walls, {0, 0, 0}, {X, 0, 0}, {X, Y, 0}, {0, Y, 0});
    face(walls, {0, 0, Z}, {X, 0, Z}, {X, Y, Z}, {0, Y, Z});
    face(walls, {0, 0, 0}, {0, 0, Z}, {0, Y, Z}, {0, Y, 0});
    face(walls, {X, 0, 0}, {X, 0, Z}, {X, Y, Z}, {X, Y, 0});
    mesh("Floor", kFloor, floor);
    mesh("Ceiling", kCeiling, ceiling);
    mesh("Walls", kWall, walls);

    // Panes 0.16 m along the wall by 0.30 m, 2 cm apart, from 2.5 m up.
    std::vector<Quad> panes;
    const float paneWidth = 0.16f, paneHeight = 0.30f, gap = 0.02f, bottom = 2.5f;
    for (const float wallX : {0.01f, X - 0.01f})
        for (int window = 0; window < 10; ++window) {
            const float centre = -1.2f - 2.4f * float(window);
            const float start = centre - 0.5f * (10.0f * paneWidth + 9.0f * gap);
            for (int row = 0; row < 10; ++row)
                for (int column = 0; column < 10; ++column) {
                    const float z0 = start + float(column) * (paneWidth + gap), z1 = z0 + paneWidth;
                    const float y0 = bottom + float(row) * (paneHeight + gap), y1 = y0 + paneHeight;
                    face(panes, {wallX, y0, z0}, {wallX, y0, z1}, {wallX, y1, z1}, {wallX, y1, z0});
                }
        }
    mesh("WindowPanes", kPane, panes);

    std::vector<Quad> pillars, tables;
    auto add = [](std::vector<Quad>& to, const std::vector<Quad>& quads) { to.insert(to.end(), quads.begin(), quads.end()); };
    for (int k = 1; k <= 9; ++k) {
        const float z = -2.4f * float(k);
        add(pillars, boxQuads({3.3f, 0.0f, z - 0.3f}, {3.9f, Y, z + 0.3f}));
        add(pillars, boxQuads({8.1f, 0.0f, z - 0.3f}, {8.7f, Y, z + 0.3f}));
    }
    for (int k = 0; k < 10; ++k) {
        const float z = -1.2f - 2.4f * float(k);
        add(tables, boxQuads({5.2f, 0.0f, z - 0.4f}, {6.8f, 0.75f, z + 0.4f}));
    }
    mesh("Pillars", kStone, pillars);
    mesh("Tables", kWood, tables);

    // 20 W each (I = 20/(4π) W/sr), warm.
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 20; ++j)
            scene.lights.push_back({"Lamp" + std::to_string(i) + "_" + std::to_string(j),
                                    vec3(0.6f + 1.2f * float(i), 3.2f, -0.6f - 1.2f * float(j)), vec3(1.0f, 0.8f, 0.6f),
                                    20.0f / (4.0f * kPi) * 683.0f});

    // At the hall's end, looking down its length.
    scene.camera.position = vec3(6.0f, 1.7f, -0.5f);
    scene.camera.yfov = 1.0f;
    scene.camera.aspectRatio = 1.5f;
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
        writePngSrgb(plankTexture(), directory + "/classroom_floor.png");
        writePngSrgb(boardTexture(), directory + "/classroom_board.png");
        writeGltf(classroom(), directory, "classroom");
        writeGltf(manyLightsHall(), directory, "many_lights_hall");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "make_scenes: %s\n", e.what());
        return 1;
    }
    std::printf("wrote cornell_box.gltf, cornell_box_point.gltf, two_rooms.gltf, classroom.gltf and many_lights_hall.gltf into %s\n",
                directory.c_str());
    return 0;
}
