#include "scene/scene.h"

namespace vl {

Aabb Scene::bounds() const {
    Aabb box;
    for (const Mesh& mesh : meshes)
        for (const vec3& p : mesh.positions) box.extend(p);
    return box;
}

void Scene::moveOrigin(const glm::dvec3& newOrigin) {
    const glm::dvec3 shift = origin - newOrigin;
    const auto move = [&](vec3& p) { p = vec3(glm::dvec3(p) + shift); };
    for (Mesh& mesh : meshes)
        for (vec3& p : mesh.positions) move(p);
    for (Light& light : lights) move(light.position);
    for (Camera& camera : cameras) move(camera.position);
    origin = newOrigin;
}

size_t Scene::triangleCount() const {
    size_t count = 0;
    for (const Mesh& mesh : meshes) count += mesh.triangleCount();
    return count;
}

bool Scene::hasEmitters() const {
    for (const Mesh& mesh : meshes)
        if (mesh.triangleCount() > 0 && materialOf(mesh).emissive()) return true;
    return false;
}

const Material& Scene::materialOf(const Mesh& mesh) const {
    static const Material kDefault{};
    return mesh.material >= 0 ? materials[static_cast<size_t>(mesh.material)] : kDefault;
}

}  // namespace vl
