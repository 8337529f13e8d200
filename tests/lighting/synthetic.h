// Synthetic VoxelScenes and light-only Scenes for the lighting tests, built in code so that
// every expected value comes from geometry known by construction.
#pragma once

#include "lighting/lighting.h"
#include "voxel/voxel_scene.h"

#include <algorithm>
#include <map>
#include <tuple>

namespace vl::test {

struct SyntheticVoxel {
    vec3 albedo{0.5f};
    vec3 normal{0.0f, 0.0f, 1.0f};
    AxisWeights axisWeights{0, 0, 0, 0, 1, 0};
    float opacity = 1.0f;
    bool solid = true;
};

// Axis weights of a flat surface with unit normal n (area-weighted signed parts).
inline AxisWeights flatWeights(const vec3& n) {
    return {std::max(n.x, 0.0f), std::max(-n.x, 0.0f), std::max(n.y, 0.0f),
            std::max(-n.y, 0.0f), std::max(n.z, 0.0f), std::max(-n.z, 0.0f)};
}

inline SyntheticVoxel surfaceVoxel(const vec3& n, float albedo = 0.5f, bool solid = true) {
    SyntheticVoxel v;
    v.albedo = vec3(albedo);
    v.normal = n;
    v.axisWeights = flatWeights(n);
    v.solid = solid;
    return v;
}

class VoxelBuilder {
public:
    explicit VoxelBuilder(double voxelSize) : voxelSize_(voxelSize) {}

    void set(const ivec3& c, const SyntheticVoxel& v) { voxels_[key(c)] = v; }
    void erase(const ivec3& c) { voxels_.erase(key(c)); }
    bool has(const ivec3& c) const { return voxels_.count(key(c)) != 0; }

    VoxelScene build() const {
        VoxelScene scene;
        scene.voxelSize = voxelSize_;
        scene.sourceScene = "synthetic";
        for (const auto& [k, v] : voxels_) {  // std::map order = (x, y, z) lexicographic
            scene.coords.push_back(ivec3(std::get<0>(k), std::get<1>(k), std::get<2>(k)));
            scene.albedo.push_back(v.albedo);
            scene.normal.push_back(v.normal);
            scene.axisWeights.push_back(v.axisWeights);
            scene.opacity.push_back(v.opacity);
            scene.solid.push_back(v.solid ? 1 : 0);
        }
        return scene;
    }

private:
    using Key = std::tuple<int, int, int>;
    static Key key(const ivec3& c) { return {c.x, c.y, c.z}; }
    double voxelSize_;
    std::map<Key, SyntheticVoxel> voxels_;
};

inline size_t indexOf(const VoxelScene& scene, const ivec3& c) {
    const auto it = std::lower_bound(scene.coords.begin(), scene.coords.end(), c, [](const ivec3& a, const ivec3& b) {
        return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
    });
    return static_cast<size_t>(it - scene.coords.begin());
}

inline Light pointLight(const vec3& position, float intensity, const std::string& name = "point") {
    Light light;
    light.name = name;
    light.type = LightType::Point;
    light.position = position;
    light.intensity = intensity;
    return light;
}

inline Light directionalLight(const vec3& direction, float irradiance) {
    Light light;
    light.name = "sun";
    light.type = LightType::Directional;
    light.direction = glm::normalize(direction);
    light.intensity = irradiance;
    return light;
}

inline Scene lightsOnly(std::vector<Light> lights) {
    Scene scene;
    scene.sourcePath = "synthetic.gltf";
    scene.name = "synthetic";
    scene.lights = std::move(lights);
    return scene;
}

}  // namespace vl::test
