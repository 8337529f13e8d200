// Synthetic lit voxel scenes for the cone tests: boxes, walls and media with known radiance.
#pragma once

#include "voxel/voxel_scene.h"

#include <algorithm>
#include <map>
#include <tuple>

namespace vl::test {

struct VoxelSpec {
    vec3 radiance = vec3(0.0f);
    float opacity = 1.0f;
    bool solid = true;
    vec3 albedo = vec3(0.0f);
    vec3 normal = vec3(0.0f);
    AxisWeights axisWeights = {};
    // Per-face radiance; a scene with any directional voxel gets faceRadiance, where the
    // others show `radiance` on their faces with an axis weight.
    bool directional = false;
    FaceRadiance faces = {};
};

// Collects voxels by coordinate (a later add replaces an earlier one) and emits a
// VoxelScene sorted as voxel_scene.h requires.
class SceneBuilder {
public:
    explicit SceneBuilder(double voxelSize) : voxelSize_(voxelSize) {}

    void add(const ivec3& c, const VoxelSpec& spec) { voxels_[std::make_tuple(c.x, c.y, c.z)] = spec; }

    VoxelScene build() const {
        VoxelScene scene;
        scene.voxelSize = voxelSize_;
        scene.sourceScene = "synthetic";
        bool directional = false;
        for (const auto& entry : voxels_) directional = directional || entry.second.directional;
        for (const auto& [key, spec] : voxels_) {
            if (directional) {
                FaceRadiance faces = spec.faces;
                if (!spec.directional)
                    for (size_t f = 0; f < 6; ++f) faces[f] = spec.axisWeights[f] > 0.0f ? spec.radiance : vec3(0.0f);
                scene.faceRadiance.push_back(faces);
            }
            scene.coords.emplace_back(std::get<0>(key), std::get<1>(key), std::get<2>(key));
            scene.radiance.push_back(spec.radiance);
            scene.opacity.push_back(spec.opacity);
            scene.solid.push_back(spec.solid ? 1 : 0);
            scene.albedo.push_back(spec.albedo);
            scene.normal.push_back(spec.normal);
            scene.axisWeights.push_back(spec.axisWeights);
        }
        return scene;
    }

private:
    double voxelSize_;
    std::map<std::tuple<int, int, int>, VoxelSpec> voxels_;
};

// Closed box: interior voxels 0 … n−1 on each axis, walls `thickness` voxels thick around
// it, every wall voxel radiating `radiance` from its inward faces (edges and corners: two or
// three; the others show nothing), with inward normal (edges and corners: the normalised sum
// of their faces' normals) and albedo `albedo`.
inline VoxelScene closedBox(int n, int thickness, vec3 radiance, vec3 albedo = vec3(0.0f), double h = 0.1) {
    SceneBuilder builder(h);
    for (int x = -thickness; x < n + thickness; ++x)
        for (int y = -thickness; y < n + thickness; ++y)
            for (int z = -thickness; z < n + thickness; ++z) {
                const ivec3 c(x, y, z);
                const bool interior = glm::all(glm::greaterThanEqual(c, ivec3(0))) && glm::all(glm::lessThan(c, ivec3(n)));
                if (interior) continue;
                VoxelSpec spec;
                spec.radiance = radiance;
                spec.albedo = albedo;
                vec3 inward(0.0f);
                for (int a = 0; a < 3; ++a) {
                    if (c[a] < 0) inward[a] += 1.0f;
                    if (c[a] >= n) inward[a] -= 1.0f;
                }
                spec.normal = glm::normalize(inward);
                for (int a = 0; a < 3; ++a) {
                    if (inward[a] > 0.0f) spec.axisWeights[2 * a] = 1.0f;
                    if (inward[a] < 0.0f) spec.axisWeights[2 * a + 1] = 1.0f;
                }
                spec.directional = true;
                for (size_t f = 0; f < 6; ++f) spec.faces[f] = spec.axisWeights[f] > 0.0f ? radiance : vec3(0.0f);
                builder.add(c, spec);
            }
    return builder.build();
}

// The receiver point at the centre of the interior of closedBox(n, …).
inline vec3 boxCentre(int n, double h = 0.1) { return vec3(0.5f * float(n - 1) * float(h)); }

}  // namespace vl::test
