// Small analytic scenes for the path tracer's tests, built in code: a closed icosphere (flat
// normals, so every face is an exact plane) and an axis-aligned quad with a lightmap UV set.
#pragma once

#include "scene/scene.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"

#include <array>
#include <map>
#include <utility>
#include <vector>

namespace vl::test {

// Icosphere of `subdivisions` levels about `centre`, one vertex triple per face with the
// face normal (pointing outward; the material decides what a side does).
inline Mesh makeIcosphere(const std::string& name, vec3 centre, float radius, int subdivisions, int material) {
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    std::vector<vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                           {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    for (vec3& p : v) p = glm::normalize(p);
    std::vector<std::array<uint32_t, 3>> faces = {
        {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
        {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (int s = 0; s < subdivisions; ++s) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            const auto key = std::make_pair(std::min(a, b), std::max(a, b));
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            v.push_back(glm::normalize(v[a] + v[b]));
            const uint32_t index = static_cast<uint32_t>(v.size() - 1);
            mid[key] = index;
            return index;
        };
        std::vector<std::array<uint32_t, 3>> next;
        for (const auto& f : faces) {
            const uint32_t a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
            next.push_back({f[0], a, c});
            next.push_back({f[1], b, a});
            next.push_back({f[2], c, b});
            next.push_back({a, b, c});
        }
        faces = std::move(next);
    }
    Mesh mesh;
    mesh.name = name;
    mesh.material = material;
    for (const auto& f : faces) {
        const vec3 a = centre + radius * v[f[0]], b = centre + radius * v[f[1]], c = centre + radius * v[f[2]];
        const vec3 n = glm::normalize(glm::cross(b - a, c - a));
        for (const vec3& p : {a, b, c}) {
            mesh.indices.push_back(static_cast<uint32_t>(mesh.positions.size()));
            mesh.positions.push_back(p);
            mesh.normals.push_back(n);
        }
    }
    return mesh;
}

// The square [x0, x1] × [z0, z1] at height y, facing +Y, TEXCOORD_1 u = (x − x0)/(x1 − x0),
// v = (z − z0)/(z1 − z0) (v grows toward +Z, i.e. down the image).
inline Mesh makeFloor(const std::string& name, float x0, float x1, float z0, float z1, float y, int material) {
    Mesh mesh;
    mesh.name = name;
    mesh.material = material;
    mesh.positions = {{x0, y, z0}, {x1, y, z0}, {x1, y, z1}, {x0, y, z1}};
    mesh.normals.assign(4, vec3(0, 1, 0));
    mesh.uv1 = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    mesh.indices = {0, 2, 1, 0, 3, 2};  // counter-clockwise seen from +Y
    return mesh;
}

inline Material lambert(const std::string& name, vec3 albedo, vec3 emission = vec3(0.0f)) {
    Material m;
    m.name = name;
    m.baseColorFactor = vec4(albedo, 1.0f);
    m.metallic = 0.0f;
    m.roughness = 1.0f;
    m.emissiveFactor = emission;
    m.doubleSided = true;
    return m;
}

// Everything the path tracer needs, built once.
struct TraceFixture {
    Scene scene;
    SceneTriangles triangles;
    Bvh bvh;
    TraceScene trace;

    explicit TraceFixture(Scene s) : scene(std::move(s)) {
        triangles = gatherTriangles(scene);
        bvh = Bvh::build(triangles);
        trace = TraceScene::build(scene, triangles);
    }
};

}  // namespace vl::test
