#include "scene/scene.h"

namespace vl {

Aabb Scene::bounds() const {
    Aabb box;
    for (const Mesh& mesh : meshes)
        for (const vec3& p : mesh.positions) box.extend(p);
    return box;
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
