// Single-primitive intersection: analytic hits, hard cases (grazing, parallel, tiny,
// degenerate), the stable sphere formula, and the self-intersection offset.
#include "core/rng.h"
#include "core/sampling.h"
#include "trace/ray_offset.h"
#include "trace/sphere_intersect.h"
#include "trace/triangle_intersect.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;

namespace {

Ray makeRay(vec3 origin, vec3 direction, float tMin = 0.0f, float tMax = kInfinity) {
    Ray r;
    r.origin = origin;
    r.direction = direction;
    r.tMin = tMin;
    r.tMax = tMax;
    return r;
}

// Ray–plane distance in long double: the reference for the float results.
long double planeT(const vec3& v0, const vec3& v1, const vec3& v2, const Ray& ray) {
    long double e1[3], e2[3], n[3], w[3];
    for (int i = 0; i < 3; ++i) {
        e1[i] = (long double)v1[i] - v0[i];
        e2[i] = (long double)v2[i] - v0[i];
        w[i] = (long double)v0[i] - ray.origin[i];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const long double nw = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
    const long double nd = n[0] * ray.direction.x + n[1] * ray.direction.y + n[2] * ray.direction.z;
    return nw / nd;
}

// Both roots of |O + t d − C|² = r² in long double, from the same float inputs.
bool exactSphereRoots(vec3 centre, float radius, vec3 origin, vec3 direction, long double& t0, long double& t1) {
    long double a = 0, b = 0, c = -(long double)radius * radius;
    for (int i = 0; i < 3; ++i) {
        const long double f = (long double)origin[i] - centre[i];
        a += (long double)direction[i] * direction[i];
        b += 2 * f * direction[i];
        c += f * f;
    }
    if (b * b - 4 * a * c < 0) return false;
    const long double root = std::sqrt(b * b - 4 * a * c);
    const long double q = -0.5L * (b + (b >= 0 ? root : -root));
    t0 = std::min(c / q, q / a);
    t1 = std::max(c / q, q / a);
    return true;
}

// The textbook formula in float: what ERRATA eq. 1 warns about.
float naiveSphereNearRoot(vec3 centre, float radius, vec3 origin, vec3 direction) {
    const vec3 f = origin - centre;
    const float a = glm::dot(direction, direction), b = 2.0f * glm::dot(f, direction);
    const float c = glm::dot(f, f) - radius * radius;
    return (-b - std::sqrt(b * b - 4.0f * a * c)) / (2.0f * a);
}

}  // namespace

TEST_CASE("Triangle hit gives the analytic distance and barycentrics from either side", "[trace]") {
    const vec3 v0(0, 0, 0), v1(2, 0, 0), v2(0, 2, 0);
    TriangleHit hit;
    REQUIRE(intersectTriangle(makeRay(vec3(0.5f, 0.25f, 3.0f), vec3(0, 0, -1)), v0, v1, v2, hit));
    REQUIRE(hit.t == 3.0f);
    REQUIRE(hit.b1 == Approx(0.25f));   // x = 2·b1
    REQUIRE(hit.b2 == Approx(0.125f));  // y = 2·b2
    // From behind (the back face): same point.
    REQUIRE(intersectTriangle(makeRay(vec3(0.5f, 0.25f, -2.0f), vec3(0, 0, 1)), v0, v1, v2, hit));
    REQUIRE(hit.t == 2.0f);
    REQUIRE(hit.b1 == Approx(0.25f));
    // Pointing away, outside the triangle, and outside (tMin, tMax): no hit.
    REQUIRE_FALSE(intersectTriangle(makeRay(vec3(0.5f, 0.25f, 3.0f), vec3(0, 0, 1)), v0, v1, v2, hit));
    REQUIRE_FALSE(intersectTriangle(makeRay(vec3(1.5f, 1.5f, 3.0f), vec3(0, 0, -1)), v0, v1, v2, hit));
    REQUIRE_FALSE(intersectTriangle(makeRay(vec3(0.5f, 0.25f, 3.0f), vec3(0, 0, -1), 0.0f, 3.0f), v0, v1, v2, hit));
    REQUIRE_FALSE(intersectTriangle(makeRay(vec3(0.5f, 0.25f, 3.0f), vec3(0, 0, -1), 3.0f), v0, v1, v2, hit));
    REQUIRE(intersectTriangle(makeRay(vec3(0.5f, 0.25f, 3.0f), vec3(0, 0, -1), 2.9f, 3.1f), v0, v1, v2, hit));
}

TEST_CASE("Random rays against random triangles agree with a long double plane hit", "[trace]") {
    Pcg32 rng(11, 3);
    auto point = [&] { return vec3(rng.next1D(), rng.next1D(), rng.next1D()) * 2.0f - 1.0f; };
    int hits = 0;
    for (int i = 0; i < 20000; ++i) {
        const vec3 v0 = point(), v1 = point(), v2 = point();
        const vec3 target = point() * 0.3f + (v0 + v1 + v2) / 3.0f;
        const vec3 origin = 3.0f * point();
        const Ray ray = makeRay(origin, glm::normalize(target - origin));
        TriangleHit hit;
        if (!intersectTriangle(ray, v0, v1, v2, hit)) continue;
        ++hits;
        const long double t = planeT(v0, v1, v2, ray);
        REQUIRE(std::abs(hit.t - t) <= 1e-4L * std::max(1.0L, std::abs(t)));
        REQUIRE(hit.b1 >= 0.0f);
        REQUIRE(hit.b2 >= 0.0f);
        REQUIRE(hit.b1 + hit.b2 <= 1.0f + 1e-6f);
        // The barycentric point is where the ray is.
        const vec3 p = (1.0f - hit.b1 - hit.b2) * v0 + hit.b1 * v1 + hit.b2 * v2;
        REQUIRE(glm::length(p - ray.at(hit.t)) < 1e-4f);
    }
    REQUIRE(hits > 2000);
}

TEST_CASE("Grazing rays hit where they should and rays parallel to a triangle never do", "[trace]") {
    const vec3 v0(-1, 0, -1), v1(1, 0, -1), v2(0, 0, 1);  // in the plane y = 0
    TriangleHit hit;
    for (float angle : {1e-2f, 1e-3f, 1e-4f, 1e-5f}) {
        // Descends at `angle` and reaches y = 0 at (0, 0, 0), inside the triangle.
        const vec3 dir = glm::normalize(vec3(0.0f, -std::sin(angle), std::cos(angle)));
        const float distance = 0.5f;
        const Ray ray = makeRay(-distance * dir, dir);
        REQUIRE(intersectTriangle(ray, v0, v1, v2, hit));
        REQUIRE(std::isfinite(hit.t));
        REQUIRE(hit.t == Approx(distance).epsilon(1e-5));
        REQUIRE(glm::length(ray.at(hit.t)) < 1e-5f);
    }
    // In the plane (coplanar, through the interior), above it, below it: no hit and no NaN.
    for (float height : {0.0f, 1e-3f, -1e-3f, 1e-30f}) {
        for (const vec3 dir : {vec3(0, 0, 1), vec3(1, 0, 0), glm::normalize(vec3(1, 0, 1))}) {
            hit.t = 12345.0f;
            REQUIRE_FALSE(intersectTriangle(makeRay(vec3(0.1f, height, -2.0f) - 2.0f * dir, dir), v0, v1, v2, hit));
            REQUIRE(hit.t == 12345.0f);
        }
    }
}

TEST_CASE("A triangle 1e-6 m across is hit at its centre", "[trace]") {
    for (const vec3 centre : {vec3(0.0f), vec3(0.3f, -0.2f, 0.1f), vec3(1.0f, 1.0f, 1.0f)}) {
        const float s = 1e-6f;
        const vec3 v0 = centre + vec3(-0.5f * s, -0.29f * s, 0.0f);
        const vec3 v1 = centre + vec3(0.5f * s, -0.29f * s, 0.0f);
        const vec3 v2 = centre + vec3(0.0f, 0.58f * s, 0.0f);
        const vec3 target = (v0 + v1 + v2) / 3.0f;
        const vec3 origin = centre + vec3(0.2f, 0.3f, 1.0f);
        const Ray ray = makeRay(origin, glm::normalize(target - origin));
        TriangleHit hit;
        INFO("centre " << centre.x);
        REQUIRE(intersectTriangle(ray, v0, v1, v2, hit));
        REQUIRE(hit.t == Approx(glm::length(target - origin)).epsilon(1e-6));
        // Float rounding of vertices ~1 m from the origin is ~6e-8 m, 6% of this triangle.
        REQUIRE(hit.b1 == Approx(1.0 / 3.0).margin(0.15));
        REQUIRE(hit.b2 == Approx(1.0 / 3.0).margin(0.15));
        // Rays aimed 1e-6 m beside it miss.
        const Ray beside = makeRay(origin, glm::normalize(target + vec3(s, 0.0f, 0.0f) - origin));
        REQUIRE_FALSE(intersectTriangle(beside, v0, v1, v2, hit));
    }
}

TEST_CASE("Degenerate triangles are never hit and give no NaN", "[trace]") {
    TriangleHit hit;
    const Ray ray = makeRay(vec3(0.2f, 0.1f, 1.0f), vec3(0, 0, -1));
    // Collinear, repeated vertex, all three equal.
    REQUIRE_FALSE(intersectTriangle(ray, vec3(0, 0, 0), vec3(1, 0.5f, 0), vec3(0.4f, 0.2f, 0), hit));
    REQUIRE_FALSE(intersectTriangle(ray, vec3(0, 0, 0), vec3(0, 0, 0), vec3(1, 1, 0), hit));
    REQUIRE_FALSE(intersectTriangle(ray, vec3(0.2f, 0.1f, 0), vec3(0.2f, 0.1f, 0), vec3(0.2f, 0.1f, 0), hit));
}

TEST_CASE("Sphere roots match the analytic distances", "[trace]") {
    const vec3 centre(1.0f, 2.0f, 3.0f);
    float t = 0.0f;
    // From 5 units away along +x, radius 2: hits at 3 and 7.
    const Ray ray = makeRay(centre - vec3(5, 0, 0), vec3(1, 0, 0));
    REQUIRE(intersectSphere(centre, 2.0f, ray, t));
    REQUIRE(t == 3.0f);
    REQUIRE(intersectSphere(centre, 2.0f, makeRay(ray.origin, ray.direction, 3.5f), t));
    REQUIRE(t == 7.0f);
    REQUIRE_FALSE(intersectSphere(centre, 2.0f, makeRay(ray.origin, ray.direction, 0.0f, 2.5f), t));
    // Unnormalised direction: t in units of its length.
    REQUIRE(intersectSphere(centre, 2.0f, makeRay(ray.origin, vec3(2, 0, 0)), t));
    REQUIRE(t == 1.5f);
    // Passing 2.5 from the centre: miss; from inside: the exit.
    REQUIRE_FALSE(intersectSphere(centre, 2.0f, makeRay(centre + vec3(-5, 2.5f, 0), vec3(1, 0, 0)), t));
    REQUIRE(intersectSphere(centre, 2.0f, makeRay(centre, vec3(0, 0, -1)), t));
    REQUIRE(t == 2.0f);
}

TEST_CASE("A sphere of radius 1e6 seen from a point on its surface", "[trace]") {
    const vec3 centre(0.0f);
    const float radius = 1e6f;
    // A point on the surface as a float can hold it (0.012 m off: the float grid there is 0.06 m).
    const vec3 n = glm::normalize(vec3(0.3f, 1.0f, 0.2f));
    vec3 t, b;
    orthonormalBasis(n, t, b);
    float worstNaiveError = 0.0f;
    for (const float height : {0.0f, 1.0f}) {
        const vec3 origin = (radius + height) * n;
        for (const float degrees : {89.0f, 45.0f, 10.0f, 1.0f, 0.1f, 0.01f}) {
            const float angle = degrees * kPi / 180.0f;  // below the tangent plane
            const vec3 dir = glm::normalize(std::cos(angle) * t - std::sin(angle) * n);
            long double e0, e1;
            SphereRoots roots;
            INFO("height " << height << " angle " << degrees);
            if (!exactSphereRoots(centre, radius, origin, dir, e0, e1)) {
                // 1 m up, the horizon is 0.08° down: this ray passes above the sphere.
                REQUIRE(height == 1.0f);
                REQUIRE_FALSE(sphereRoots(centre, radius, origin, dir, roots));
                continue;
            }
            REQUIRE(sphereRoots(centre, radius, origin, dir, roots));
            // Both roots to float precision, including the one near zero that depends on c.
            REQUIRE(std::abs(roots.t0 - e0) <= 1e-6L * std::abs(e0) + 1e-9L);
            REQUIRE(std::abs(roots.t1 - e1) <= 1e-6L * std::abs(e1));
            REQUIRE(e0 > 0.0L);  // the origin is (just) outside: the near root is the hit
            float hitT;
            REQUIRE(intersectSphere(centre, radius, makeRay(origin, dir), hitT));
            REQUIRE(hitT == roots.t0);
            const float naive = naiveSphereNearRoot(centre, radius, origin, dir);
            worstNaiveError = std::max(worstNaiveError, float(std::abs(naive - e0) / e0));
        }
    }
    // The textbook formula in float loses the near root entirely (c = |f|² − r² cancels):
    // it is off by more than 2% somewhere (it returns 0 for a root at 0.0117).
    REQUIRE(worstNaiveError > 0.02f);
}

TEST_CASE("Offset ray origins do not re-hit their own surface at 1e-3 and 1e3 scale", "[trace]") {
    for (const float scale : {1e-3f, 1.0f, 1e3f})
    for (const bool centred : {false, true}) {
        // A quad (two triangles) of size `scale` at a position of magnitude ~`scale`, or
        // centred on the origin as scenes are in their local frame (where a fixed offset
        // near the origin would be a large part of a small scene), tilted so no coordinate
        // is axis-aligned.
        INFO("scale " << scale << (centred ? ", centred" : ""));
        const vec3 u = scale * glm::normalize(vec3(1.0f, 0.2f, -0.3f));
        const vec3 v = scale * glm::normalize(glm::cross(glm::normalize(vec3(0.1f, 1.0f, 0.4f)), u / scale));
        const vec3 base = centred ? -0.5f * (u + v) : scale * vec3(1.3f, 0.7f, -2.1f);
        const vec3 quad[4] = {base, base + u, base + u + v, base + v};
        const vec3 normal = glm::normalize(glm::cross(u, v));
        Pcg32 rng(7, 1);
        int selfHitsWithoutOffset = 0;
        for (int i = 0; i < 20000; ++i) {
            // Hit the quad from above at a random point, as a path tracer would.
            const vec3 target = base + (0.05f + 0.9f * rng.next1D()) * u + (0.05f + 0.9f * rng.next1D()) * v;
            const vec3 from = target + scale * (normal + 0.3f * vec3(rng.next1D() - 0.5f, 0.0f, rng.next1D() - 0.5f));
            const Ray in = makeRay(from, glm::normalize(target - from));
            TriangleHit hit;
            const bool first = intersectTriangle(in, quad[0], quad[1], quad[2], hit);
            const vec3* tri = first ? quad : nullptr;
            const vec3 second[3] = {quad[0], quad[2], quad[3]};
            if (!first) {
                REQUIRE(intersectTriangle(in, second[0], second[1], second[2], hit));
                tri = second;
            }
            const vec3 p = (1.0f - hit.b1 - hit.b2) * tri[0] + hit.b1 * tri[1] + hit.b2 * tri[2];
            // Leave at a grazing angle (0.001 to 0.01 rad above the surface) in a random
            // direction along it.
            const float phi = 2.0f * kPi * rng.next1D(), elevation = 1e-3f + 9e-3f * rng.next1D();
            const vec3 along = std::cos(phi) * glm::normalize(u) + std::sin(phi) * glm::normalize(v);
            const vec3 out = glm::normalize(std::cos(elevation) * along + std::sin(elevation) * normal);
            const vec3 origin = offsetRayOrigin(p, normal, scale);
            REQUIRE(glm::length(origin - p) <= 1e-4f * (glm::length(p) + scale));  // small for its scale
            TriangleHit again;
            REQUIRE_FALSE(intersectTriangle(makeRay(origin, out), quad[0], quad[1], quad[2], again));
            REQUIRE_FALSE(intersectTriangle(makeRay(origin, out), second[0], second[1], second[2], again));
            // The same ray from the raw hit point does re-hit sometimes: the offset matters.
            selfHitsWithoutOffset += intersectTriangle(makeRay(p, out), quad[0], quad[1], quad[2], again) ||
                                     intersectTriangle(makeRay(p, out), second[0], second[1], second[2], again);
        }
        INFO("scale " << scale);
        REQUIRE(selfHitsWithoutOffset > 100);
    }
}
