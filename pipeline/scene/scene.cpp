#include "scene/scene.h"

#include "core/error.h"
#include "core/image_io.h"

#include <cmath>
#include <string>

namespace vl {

const char* lightBakeName(LightBake mode) {
    return mode == LightBake::Indirect ? "indirect" : mode == LightBake::Shadowmask ? "shadowmask" : "all";
}

bool parseLightBake(const std::string& name, LightBake& mode) {
    for (LightBake known : {LightBake::All, LightBake::Indirect, LightBake::Shadowmask})
        if (name == lightBakeName(known)) {
            mode = known;
            return true;
        }
    return false;
}

Aabb Scene::bounds() const {
    Aabb box;
    for (const Mesh& mesh : meshes)
        for (const vec3& p : mesh.positions) box.extend(p);
    return box;
}

void Scene::moveOrigin(const glm::dvec3& newOrigin) {
    const glm::dvec3 shift = glm::transpose(frame) * (origin - newOrigin);
    const auto move = [&](vec3& p) { p = vec3(glm::dvec3(p) + shift); };
    for (Mesh& mesh : meshes)
        for (vec3& p : mesh.positions) move(p);
    for (Light& light : lights) move(light.position);
    for (Camera& camera : cameras) move(camera.position);
    origin = newOrigin;
}

void Scene::turnFrame(const glm::dmat3& newFrame) {
    const glm::dmat3 turn = glm::transpose(newFrame) * frame;  // old local → new local
    const auto turned = [&](vec3& v) { v = vec3(turn * glm::dvec3(v)); };
    for (Mesh& mesh : meshes) {
        for (vec3& p : mesh.positions) turned(p);
        for (vec3& n : mesh.normals) turned(n);
    }
    for (Light& light : lights) {
        turned(light.position);
        turned(light.direction);
    }
    for (Camera& camera : cameras) {
        turned(camera.position);
        turned(camera.forward);
        turned(camera.up);
    }
    frame = newFrame;
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

vec3 Sky::meanRadiance() const {
    if (!image || image->texels.empty()) return radiance;
    glm::dvec3 sum(0.0);
    double weights = 0.0;
    for (int y = 0; y < image->height; ++y) {
        const double w = std::sin(kPi * (double(y) + 0.5) / double(image->height));
        for (int x = 0; x < image->width; ++x) sum += w * glm::dvec3(image->texels[size_t(y) * size_t(image->width) + size_t(x)]);
        weights += w * double(image->width);
    }
    return radiance + intensity * vec3(sum / weights);
}

std::shared_ptr<const SkyImage> loadSkyImage(const std::string& path) {
    const Image image = readLinearImage(path);
    if (image.width < 2 || image.height < 1 || image.channels < 1)
        throw InputError(path + ": a sky image needs at least 2 x 1 pixels, not " + std::to_string(image.width) + " x " +
                         std::to_string(image.height));
    auto sky = std::make_shared<SkyImage>();
    sky->path = path;
    sky->width = image.width;
    sky->height = image.height;
    sky->texels.resize(size_t(image.width) * size_t(image.height));
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const vec3 c = image.channels >= 3 ? image.rgb(x, y) : vec3(image.at(x, y, 0));
            if (!isFinite(c) || glm::min(c.x, glm::min(c.y, c.z)) < 0.0f)
                throw InputError(path + ": the sky image's pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                 ") is negative or not finite");
            sky->texels[size_t(y) * size_t(image.width) + size_t(x)] = c;
        }
    return sky;
}

}  // namespace vl
