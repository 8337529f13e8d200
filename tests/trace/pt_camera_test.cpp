// Camera rays: the thin lens of ERRATA eq. 10 reduces to the pinhole exactly at aperture 0,
// focuses every lens sample of a pixel on the same focal-plane point, and the field of view
// and pixel filters land where the geometry says.
#include "trace/camera.h"

#include "core/rng.h"
#include "scene/scene.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>

using namespace vl;

namespace {

Camera tiltedCamera(float aperture) {
    Camera c;
    c.position = vec3(0.5f, 1.0f, 3.0f);
    c.forward = glm::normalize(vec3(-0.1f, -0.2f, -1.0f));
    c.up = glm::normalize(glm::cross(glm::cross(c.forward, vec3(0, 1, 0)), c.forward));
    c.yfov = 0.7f;
    c.apertureRadius = aperture;
    c.focusDistance = 2.5f;
    return c;
}

}  // namespace

TEST_CASE("Thin lens with aperture 0 gives the pinhole ray bit for bit", "[trace]") {
    const CameraModel cam = makeCameraModel(tiltedCamera(0.0f), 64, 48);
    Pcg32 rng(1, 2);
    for (int i = 0; i < 10000; ++i) {
        const vec2 film(rng.next1D() * 64.0f, rng.next1D() * 48.0f);
        const vec2 lens(rng.next1D(), rng.next1D());
        const Ray a = thinLensRay(cam, film, lens);
        const Ray b = pinholeRay(cam, film);
        REQUIRE(std::memcmp(&a.origin, &b.origin, sizeof(vec3)) == 0);
        REQUIRE(std::memcmp(&a.direction, &b.direction, sizeof(vec3)) == 0);
    }
}

TEST_CASE("Thin lens rays start on the aperture disk and meet the pinhole ray on the focal plane", "[trace]") {
    const Camera camera = tiltedCamera(0.05f);
    const CameraModel cam = makeCameraModel(camera, 64, 48);
    Pcg32 rng(3, 4);
    double maxRadius = 0.0;
    for (int i = 0; i < 10000; ++i) {
        const vec2 film(rng.next1D() * 64.0f, rng.next1D() * 48.0f);
        const Ray a = thinLensRay(cam, film, vec2(rng.next1D(), rng.next1D()));
        const Ray p = pinholeRay(cam, film);
        const vec3 offset = a.origin - camera.position;
        REQUIRE(glm::length(offset) <= camera.apertureRadius * (1.0f + 1e-5f));
        REQUIRE(std::abs(glm::dot(offset, cam.forward)) < 1e-6f);  // the lens lies in the film plane
        maxRadius = std::max(maxRadius, double(glm::length(offset)));
        REQUIRE(glm::length(a.direction) == Approx(1.0f).margin(1e-6));
        // Both rays reach the plane at focus distance along forward at the same point.
        const float ta = (camera.focusDistance - glm::dot(offset, cam.forward)) / glm::dot(a.direction, cam.forward);
        const float tp = camera.focusDistance / glm::dot(p.direction, cam.forward);
        const vec3 qa = a.origin + ta * a.direction, qp = p.origin + tp * p.direction;
        REQUIRE(glm::length(qa - qp) < 2e-5f * camera.focusDistance);
    }
    REQUIRE(maxRadius > 0.9 * camera.apertureRadius);  // the disk is actually used
}

TEST_CASE("Pinhole rays span the vertical field of view and the image aspect", "[trace]") {
    Camera c;
    c.position = vec3(0.0f);
    c.forward = vec3(0, 0, -1);
    c.up = vec3(0, 1, 0);
    c.yfov = 0.686048f;
    const CameraModel cam = makeCameraModel(c, 200, 100);
    const Ray centre = pinholeRay(cam, vec2(100.0f, 50.0f));
    REQUIRE(centre.direction.z == Approx(-1.0f));
    const Ray top = pinholeRay(cam, vec2(100.0f, 0.0f));  // top edge of the film
    REQUIRE(std::atan2(top.direction.y, -top.direction.z) == Approx(0.5 * 0.686048).epsilon(1e-5));
    const Ray right = pinholeRay(cam, vec2(200.0f, 50.0f));
    REQUIRE(right.direction.x / -right.direction.z == Approx(2.0 * std::tan(0.5 * 0.686048)).epsilon(1e-5));
}

TEST_CASE("Pixel filters: the tent spans one pixel either side of the centre and the box the pixel", "[trace]") {
    Pcg32 rng(5, 6);
    double tentMean = 0.0, tentAbs = 0.0;
    constexpr int n = 100000;
    for (int i = 0; i < n; ++i) {
        const vec2 u(rng.next1D(), rng.next1D());
        const vec2 t = pixelSamplePoint(10, 20, u, PixelFilter::Tent);
        REQUIRE(t.x >= 9.5f);
        REQUIRE(t.x < 11.5f);
        REQUIRE(t.y >= 19.5f);
        REQUIRE(t.y < 21.5f);
        tentMean += t.x - 10.5;
        tentAbs += std::abs(t.x - 10.5);
        const vec2 b = pixelSamplePoint(10, 20, u, PixelFilter::Box);
        REQUIRE(b.x >= 10.0f);
        REQUIRE(b.x < 11.0f);
    }
    // Tent on [−1, 1]: mean 0, E|x| = 1/3.
    REQUIRE(std::abs(tentMean / n) < 0.005);
    REQUIRE(tentAbs / n == Approx(1.0 / 3.0).epsilon(0.01));
}

TEST_CASE("The default camera frames the scene bounds", "[trace]") {
    const Aabb box{vec3(-1, 0, -2), vec3(3, 2, 0)};
    const Camera c = defaultCamera(box, 1.5f);
    const CameraModel cam = makeCameraModel(c, 150, 100);
    // Every corner of the box projects inside the film.
    for (int i = 0; i < 8; ++i) {
        const vec3 corner((i & 1) ? box.upper.x : box.lower.x, (i & 2) ? box.upper.y : box.lower.y,
                          (i & 4) ? box.upper.z : box.lower.z);
        const vec3 d = corner - cam.position;
        const float z = glm::dot(d, cam.forward);
        REQUIRE(z > 0.0f);
        REQUIRE(std::abs(glm::dot(d, cam.right) / z) <= cam.tanHalfFovY * cam.aspect);
        REQUIRE(std::abs(glm::dot(d, cam.up) / z) <= cam.tanHalfFovY);
    }
}
