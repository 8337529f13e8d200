// Scenes of axis-aligned rooms built in code for tests of any stage: every wall is its own
// mesh with TEXCOORD_1 covering [0,1]², so per-mesh lightmaps (LightmapSettings::atlasPerMesh)
// name each wall.
#pragma once

#include "scene/scene.h"

#include <string>

namespace vl::test {

// Adds a quad with corners a, b, c, d (counter-clockwise seen from its lit side).
inline void addQuad(Scene& scene, const std::string& name, int material, vec3 a, vec3 b, vec3 c, vec3 d) {
    Mesh mesh;
    mesh.name = name;
    mesh.material = material;
    mesh.positions = {a, b, c, d};
    const vec3 n = glm::normalize(glm::cross(b - a, d - a));
    mesh.normals = {n, n, n, n};
    mesh.uv1 = {vec2(0, 1), vec2(1, 1), vec2(1, 0), vec2(0, 0)};
    mesh.indices = {0, 1, 2, 0, 2, 3};
    scene.meshes.push_back(mesh);
}

// A closed box [lo, hi] with its six faces turned inward, meshes named prefix + face.
inline void addRoom(Scene& scene, const std::string& prefix, int material, vec3 lo, vec3 hi) {
    const vec3 p000(lo.x, lo.y, lo.z), p100(hi.x, lo.y, lo.z), p010(lo.x, hi.y, lo.z), p110(hi.x, hi.y, lo.z);
    const vec3 p001(lo.x, lo.y, hi.z), p101(hi.x, lo.y, hi.z), p011(lo.x, hi.y, hi.z), p111(hi.x, hi.y, hi.z);
    addQuad(scene, prefix + "floor", material, p000, p001, p101, p100);    // normal +Y
    addQuad(scene, prefix + "ceiling", material, p010, p110, p111, p011);  // normal −Y
    addQuad(scene, prefix + "wall-x", material, p000, p010, p011, p001);   // at lo.x, normal +X
    addQuad(scene, prefix + "wall+x", material, p100, p101, p111, p110);   // at hi.x, normal −X
    addQuad(scene, prefix + "wall-z", material, p000, p100, p110, p010);   // at lo.z, normal +Z
    addQuad(scene, prefix + "wall+z", material, p001, p011, p111, p101);   // at hi.z, normal −Z
}

inline int addLambert(Scene& scene, vec3 albedo, vec3 emission = vec3(0.0f)) {
    Material m;
    m.baseColorFactor = vec4(albedo, 1.0f);
    m.emissiveFactor = emission;
    m.metallic = 0.0f;
    scene.materials.push_back(m);
    return static_cast<int>(scene.materials.size()) - 1;
}

inline Light pointLightAt(vec3 position, float wattsPerSr) {
    Light light;
    light.name = "lamp";
    light.type = LightType::Point;
    light.position = position;
    light.intensity = wattsPerSr;
    return light;
}

}  // namespace vl::test
