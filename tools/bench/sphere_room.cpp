#include "bench/sphere_room.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace vl {
namespace {

constexpr int kSpheresPerSide = 8;  // an 8 × 8 grid of spheres
constexpr int kCellsPerSide = 9;    // the atlas's cells: 64 spheres, 6 walls, the rest empty
constexpr float kRoomSize = 4.0f, kRoomHeight = 2.5f, kSphereRadius = 0.15f;
// A cell's margin in UV: the charts stay a texel or more apart at any atlas from 256².
constexpr float kCellMargin = 0.06f;

// The UV of a cell's point (u, v) ∈ [0, 1]², inside its margin.
vec2 cellUv(int cell, float u, float v) {
    const float size = 1.0f / float(kCellsPerSide);
    const float x = float(cell % kCellsPerSide), y = float(cell / kCellsPerSide);
    return vec2((x + kCellMargin + u * (1.0f - 2.0f * kCellMargin)) * size,
                (y + kCellMargin + v * (1.0f - 2.0f * kCellMargin)) * size);
}

// A quad with corners a, b, c, d (counter-clockwise seen from its front) in its own cell.
Mesh quad(const std::string& name, int material, int cell, vec3 a, vec3 b, vec3 c, vec3 d) {
    Mesh mesh;
    mesh.name = mesh.node = name;
    mesh.material = material;
    mesh.positions = {a, b, c, d};
    const vec3 n = glm::normalize(glm::cross(b - a, d - a));
    mesh.normals = {n, n, n, n};
    mesh.uv1 = {cellUv(cell, 0, 1), cellUv(cell, 1, 1), cellUv(cell, 1, 0), cellUv(cell, 0, 0)};
    mesh.indices = {0, 1, 2, 0, 2, 3};
    return mesh;
}

// A latitude-longitude sphere of `rings` rings and 2·rings segments: 4·rings² − 4·rings
// triangles; its UV1 the (longitude, latitude) rectangle in its cell.
Mesh sphere(const std::string& name, int material, int cell, vec3 centre, float radius, int rings) {
    Mesh mesh;
    mesh.name = mesh.node = name;
    mesh.material = material;
    const int segments = 2 * rings;
    for (int i = 0; i <= rings; ++i) {
        const float theta = kPi * float(i) / float(rings);
        for (int j = 0; j <= segments; ++j) {
            const float phi = 2.0f * kPi * float(j) / float(segments);
            const vec3 n(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
            mesh.positions.push_back(centre + radius * n);
            mesh.normals.push_back(n);
            mesh.uv1.push_back(cellUv(cell, float(j) / float(segments), float(i) / float(rings)));
        }
    }
    const auto at = [&](int i, int j) { return uint32_t(i * (segments + 1) + j); };
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            // The poles' rings hold one triangle a segment (the other would have no area).
            if (i > 0) mesh.indices.insert(mesh.indices.end(), {at(i, j), at(i, j + 1), at(i + 1, j)});
            if (i + 1 < rings) mesh.indices.insert(mesh.indices.end(), {at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)});
        }
    return mesh;
}

int lambert(Scene& scene, const std::string& name, vec3 albedo) {
    Material m;
    m.name = name;
    m.baseColorFactor = vec4(albedo, 1.0f);
    m.metallic = 0.0f;
    scene.materials.push_back(m);
    return int(scene.materials.size()) - 1;
}

}  // namespace

Scene sphereRoom(size_t triangles) {
    Scene scene;
    scene.sourcePath = "sphere room (" + std::to_string(triangles) + " triangles)";
    const int wall = lambert(scene, "wall", vec3(0.7f));
    const int floor = lambert(scene, "floor", vec3(0.5f, 0.45f, 0.4f));
    const int ball = lambert(scene, "sphere", vec3(0.6f, 0.3f, 0.25f));
    const float h = kRoomSize / 2.0f, top = kRoomHeight;
    const vec3 p000(-h, 0, -h), p100(h, 0, -h), p010(-h, top, -h), p110(h, top, -h);
    const vec3 p001(-h, 0, h), p101(h, 0, h), p011(-h, top, h), p111(h, top, h);
    int cell = kSpheresPerSide * kSpheresPerSide;
    scene.meshes.push_back(quad("floor", floor, cell++, p000, p001, p101, p100));
    scene.meshes.push_back(quad("ceiling", wall, cell++, p010, p110, p111, p011));
    scene.meshes.push_back(quad("wall-x", wall, cell++, p000, p010, p011, p001));
    scene.meshes.push_back(quad("wall+x", wall, cell++, p100, p101, p111, p110));
    scene.meshes.push_back(quad("wall-z", wall, cell++, p000, p100, p110, p010));
    scene.meshes.push_back(quad("wall+z", wall, cell++, p001, p011, p111, p101));
    // 4r² − 4r triangles a sphere of r rings: the spheres take r or r + 1 rings, as many of
    // each as puts the total nearest what was asked.
    const size_t spheres = size_t(kSpheresPerSide) * kSpheresPerSide;
    const double wanted = double(triangles > 12 ? triangles - 12 : 0);
    const auto sphereTriangles = [](int r) { return 4.0 * r * r - 4.0 * r; };
    const int rings = std::max(2, int(std::floor(0.5 + std::sqrt(0.25 + wanted / double(spheres) / 4.0))));
    const double step = sphereTriangles(rings + 1) - sphereTriangles(rings);
    const int finer = int(std::clamp(std::lround((wanted - double(spheres) * sphereTriangles(rings)) / step), 0L,
                                     long(spheres)));
    const float spacing = kRoomSize / float(kSpheresPerSide + 1);
    for (int k = 0; k < kSpheresPerSide * kSpheresPerSide; ++k) {
        const int i = k % kSpheresPerSide, j = k / kSpheresPerSide;
        // Two layers of height, so spheres shade the floor and each other.
        const vec3 centre(-h + spacing * float(i + 1), kSphereRadius + (((i + j) % 2) ? 0.6f : 0.05f),
                          -h + spacing * float(j + 1));
        scene.meshes.push_back(
            sphere("sphere " + std::to_string(k), ball, k, centre, kSphereRadius, k < finer ? rings + 1 : rings));
    }
    Light lamp;
    lamp.name = "lamp";
    lamp.type = LightType::Point;
    lamp.position = vec3(0.3f, top - 0.3f, -0.2f);
    lamp.intensity = 20.0f;
    scene.lights.push_back(lamp);
    Camera camera;
    camera.name = "corner";
    camera.position = vec3(-h + 0.3f, 1.6f, h - 0.3f);
    camera.forward = glm::normalize(vec3(h, 0.4f, -h) - camera.position);
    camera.up = glm::normalize(glm::cross(glm::cross(camera.forward, vec3(0, 1, 0)), camera.forward));
    scene.cameras.push_back(camera);
    return scene;
}

}  // namespace vl
