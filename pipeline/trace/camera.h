// Primary rays: pinhole and thin-lens cameras (ERRATA eq. 10) over film coordinates in
// pixels (x right, y down from the top row), and the pixel filters (tent of eq. 11, box).
// makeCameraModel takes a scene Camera (or defaultCamera's view framing the scene bounds)
// and an image size; the ray functions are VL_HOSTDEV.
#pragma once

#include "core/aabb.h"
#include "core/math.h"
#include "core/ray.h"
#include "core/sampling.h"

#include <cstdint>

namespace vl {

struct Camera;

enum class PixelFilter : uint32_t {
    Tent = 0,  // ERRATA eq. 11: offsets in [−1, 1) pixel about the centre, triangular density
    Box = 1,   // uniform over the pixel (Cycles' 1-pixel box filter)
};

struct CameraModel {
    vec3 position{0.0f};
    vec3 forward{0.0f, 0.0f, -1.0f};
    vec3 right{1.0f, 0.0f, 0.0f};
    vec3 up{0.0f, 1.0f, 0.0f};
    float tanHalfFovY = 0.4f;
    float aspect = 1.0f;        // width / height of the film
    float apertureRadius = 0.0f;
    float focusDistance = 1.0f;  // along forward
    int width = 1;
    int height = 1;
};

// The film point of a pixel sample: pixel (x, y), uniform u in [0, 1)².
VL_HOSTDEV inline vec2 pixelSamplePoint(int x, int y, vec2 u, PixelFilter filter) {
    if (filter == PixelFilter::Box) return vec2(static_cast<float>(x) + u.x, static_cast<float>(y) + u.y);
    return vec2(static_cast<float>(x) + 0.5f + sampleTent(u.x), static_cast<float>(y) + 0.5f + sampleTent(u.y));
}

// Unnormalised direction through film point p (pixels), forward component exactly 1.
VL_HOSTDEV inline vec3 cameraDirectionUnscaled(const CameraModel& c, vec2 p) {
    const float sx = (2.0f * p.x / static_cast<float>(c.width) - 1.0f) * c.tanHalfFovY * c.aspect;
    const float sy = (1.0f - 2.0f * p.y / static_cast<float>(c.height)) * c.tanHalfFovY;
    return c.forward + sx * c.right + sy * c.up;
}

VL_HOSTDEV inline Ray pinholeRay(const CameraModel& c, vec2 filmPoint) {
    Ray ray;
    ray.origin = c.position;
    ray.direction = glm::normalize(cameraDirectionUnscaled(c, filmPoint));
    return ray;
}

// ERRATA eq. 10: origin = P_c + A(r cos φ · a_x + r sin φ · a_y), (r, φ) a concentric disk
// sample; direction toward the point where the pinhole ray meets the focal plane. The lens
// offset is exactly zero when the aperture is, so aperture 0 gives the pinhole ray bit for
// bit.
VL_HOSTDEV inline Ray thinLensRay(const CameraModel& c, vec2 filmPoint, vec2 lensSample) {
    Ray ray = pinholeRay(c, filmPoint);
    if (!(c.apertureRadius > 0.0f)) return ray;
    const vec2 disk = sampleConcentricDisk(lensSample) * c.apertureRadius;
    const vec3 lensOffset = disk.x * c.right + disk.y * c.up;
    // The pinhole direction scaled so its forward component is the focus distance.
    const vec3 toFocus = cameraDirectionUnscaled(c, filmPoint) * c.focusDistance;
    ray.origin = c.position + lensOffset;
    ray.direction = glm::normalize(toFocus - lensOffset);
    return ray;
}

// Host helpers: the model for a scene camera at an image size (yfov is kept, the aspect is
// the image's: a camera's aspectRatio only picks the default image size), and a view of the
// scene bounds from +Z when the scene has no camera.
CameraModel makeCameraModel(const Camera& camera, int width, int height);
Camera defaultCamera(const Aabb& sceneBounds, float aspect);

}  // namespace vl
