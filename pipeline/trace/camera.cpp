#include "trace/camera.h"

#include "scene/scene.h"

#include <cmath>

namespace vl {

CameraModel makeCameraModel(const Camera& camera, int width, int height) {
    CameraModel c;
    c.position = camera.position;
    c.forward = glm::normalize(camera.forward);
    c.right = glm::normalize(glm::cross(c.forward, camera.up));
    c.up = glm::cross(c.right, c.forward);
    c.tanHalfFovY = std::tan(0.5f * camera.yfov);
    c.width = width;
    c.height = height;
    c.aspect = static_cast<float>(width) / static_cast<float>(height);
    c.apertureRadius = camera.apertureRadius;
    c.focusDistance = camera.focusDistance;
    return c;
}

Camera defaultCamera(const Aabb& sceneBounds, float aspect) {
    Camera camera;
    camera.name = "default";
    camera.yfov = 0.8f;
    const Aabb box = sceneBounds.empty() ? Aabb{vec3(-1.0f), vec3(1.0f)} : sceneBounds;
    const vec3 centre = box.centre();
    // A scene flat along every axis (a point) still gets a camera a unit away; any other
    // scene's view scales with it (a 1 mm scene is framed like a 1 m one).
    const float diagonal = glm::length(box.extent());
    const float radius = diagonal > 0.0f ? 0.5f * diagonal : 1.0f;
    // Fit the bounding sphere into the narrower of the two fields of view.
    const float halfY = 0.5f * camera.yfov;
    const float halfX = std::atan(std::tan(halfY) * glm::max(aspect, 1e-3f));
    const float distance = radius / std::sin(glm::min(halfX, halfY));
    camera.position = centre + vec3(0.0f, 0.0f, distance);
    camera.forward = vec3(0.0f, 0.0f, -1.0f);
    camera.up = vec3(0.0f, 1.0f, 0.0f);
    camera.focusDistance = distance;
    return camera;
}

}  // namespace vl
