#include "bake/lightmap_sides.h"

#include "core/error.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "trace/bvh_traverse.h"
#include "trace/ray_offset.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <vector>

namespace vl {

LightmapSide parseLightmapSide(const std::string& text) {
    if (text == "front") return LightmapSide::Front;
    if (text == "inside") return LightmapSide::Inside;
    throw SettingsError("setting lightmap-side = '" + text + "' is not one of front, inside");
}

const char* toString(LightmapSide side) { return side == LightmapSide::Front ? "front" : "inside"; }

namespace {

constexpr int kSideRaysPerAxis = 4;
constexpr int kClearlyFewer = 4;  // of the 16 rays

// Rays of a 4 × 4 jittered cosine fan about `normal` from `origin` that leave the scene.
int escapes(const BvhView& bvh, const vec3& origin, const vec3& normal, Pcg32& rng) {
    vec3 t, b;
    orthonormalBasis(normal, t, b);
    int open = 0;
    for (int i = 0; i < kSideRaysPerAxis; ++i)
        for (int j = 0; j < kSideRaysPerAxis; ++j) {
            vec2 u;
            rng.next2D(u.x, u.y);
            const vec3 d = sampleCosineHemisphere(vec2((float(i) + u.x) / kSideRaysPerAxis, (float(j) + u.y) / kSideRaysPerAxis));
            Ray ray;
            ray.origin = origin;
            ray.direction = glm::normalize(d.x * t + d.y * b + d.z * normal);
            if (!intersectAny(bvh, ray)) ++open;
        }
    return open;
}

}  // namespace

size_t orientLightmapSamples(SurfaceSampleSet& samples, const BvhView& bvh, const TraceSceneView& scene) {
    if (samples.samples.empty() || scene.triangleCount == 0) return 0;
    // The double-sided triangles the samples lie on, in triangle order.
    std::vector<uint8_t> held(scene.triangleCount, 0);
    for (const SurfaceSample& s : samples.samples)
        if (s.triangle < scene.triangleCount && scene.materials[scene.materialIds[s.triangle]].doubleSided) held[s.triangle] = 1;
    std::vector<uint32_t> triangles;
    for (uint32_t t = 0; t < scene.triangleCount; ++t)
        if (held[t]) triangles.push_back(t);
    std::vector<uint8_t> turn(scene.triangleCount, 0);
    tbb::parallel_for(size_t(0), triangles.size(), [&](size_t k) {
        const uint32_t t = triangles[k];
        const vec3* v = scene.vertices + 3 * size_t(t);
        const vec3 cross = glm::cross(v[1] - v[0], v[2] - v[0]);
        const float area2 = glm::length(cross);
        if (!(area2 > 0.0f)) return;
        const vec3 n = cross / area2, centroid = (v[0] + v[1] + v[2]) / 3.0f;
        Pcg32 rng = Pcg32::forItem(t, 0, 0x51de);
        const int front = escapes(bvh, offsetRayOrigin(centroid, n, bvh.extent), n, rng);
        const int back = escapes(bvh, offsetRayOrigin(centroid, -n, bvh.extent), -n, rng);
        if (back + kClearlyFewer <= front) turn[t] = 1;
    });
    size_t turned = 0;
    for (uint32_t t : triangles) turned += turn[t];
    if (turned == 0) return 0;
    tbb::parallel_for(size_t(0), samples.samples.size(), [&](size_t k) {
        SurfaceSample& s = samples.samples[k];
        if (s.triangle < scene.triangleCount && turn[s.triangle]) s.normal = -s.normal;
    });
    return turned;
}

}  // namespace vl
