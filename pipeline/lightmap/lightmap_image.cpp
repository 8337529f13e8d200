#include "lightmap/lightmap_image.h"

#include "core/error.h"
#include "export/lightmap_encoding.h"
#include "lighting/direct_light.h"
#include "trace/bvh_traverse.h"
#include "trace/trace_scene.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace vl {

namespace {

vec3 texel(const Image& image, int x, int y) {
    x = std::clamp(x, 0, image.width - 1);
    y = std::clamp(y, 0, image.height - 1);
    return image.rgb(x, y);
}

// Bilinear between texel centres, clamped to the edge, of what `at(x, y)` gives (x, y clamped).
template <typename At>
auto bilinear(const Image& texels, vec2 uv, At at) -> decltype(at(0, 0)) {
    using Value = decltype(at(0, 0));
    if (texels.empty() || !std::isfinite(uv.x) || !std::isfinite(uv.y)) return Value(0.0f);
    // Far outside the image every texel clamps to the edge: keep the float → int exact.
    const float px = std::clamp(uv.x * float(texels.width) - 0.5f, -1.0f, float(texels.width));
    const float py = std::clamp(uv.y * float(texels.height) - 0.5f, -1.0f, float(texels.height));
    const float fx0 = std::floor(px), fy0 = std::floor(py);
    const int x0 = int(fx0), y0 = int(fy0);
    const float ax = px - fx0, ay = py - fy0;
    const Value top = glm::mix(at(x0, y0), at(x0 + 1, y0), ax);
    const Value bottom = glm::mix(at(x0, y0 + 1), at(x0 + 1, y0 + 1), ax);
    return glm::mix(top, bottom, ay);
}

}  // namespace

// Its barycentrics in the triangle's plane in double: a sample's position is the mean of several
// hits, and its uv must not drift by a texel on a large triangle.
vec2 lightmapUvAt(const Mesh& mesh, uint32_t localTriangle, const vec3* corners, const vec3& point) {
    const glm::dvec3 a(corners[0]), e1 = glm::dvec3(corners[1]) - a, e2 = glm::dvec3(corners[2]) - a;
    const glm::dvec3 p = glm::dvec3(point) - a;
    const double d11 = glm::dot(e1, e1), d12 = glm::dot(e1, e2), d22 = glm::dot(e2, e2);
    const double p1 = glm::dot(p, e1), p2 = glm::dot(p, e2);
    const double det = d11 * d22 - d12 * d12;
    const double b1 = det > 0.0 ? (d22 * p1 - d12 * p2) / det : 0.0;
    const double b2 = det > 0.0 ? (d11 * p2 - d12 * p1) / det : 0.0;
    const uint32_t* index = &mesh.indices[3 * size_t(localTriangle)];
    for (int k = 0; k < 3; ++k)
        if (index[k] >= mesh.uv1.size()) return vec2(NAN);  // the lightmap left it out too (receivers.cpp)
    const glm::dvec2 uv = (1.0 - b1 - b2) * glm::dvec2(mesh.uv1[index[0]]) + b1 * glm::dvec2(mesh.uv1[index[1]]) +
                          b2 * glm::dvec2(mesh.uv1[index[2]]);
    return vec2(uv);
}

Image shippedLightmapTexels(const Image& total) { return decodeRgbm(encodeRgbm(total)); }

Image shippedShadowmask(const Image& mask) {
    return mask.empty() ? Image() : decodeShadowmask(mask.width, mask.height, shadowmaskBytes(mask));
}

vec3 sampleLightmap(const Image& texels, vec2 uv) {
    return bilinear(texels, uv, [&](int x, int y) { return texel(texels, x, y); });
}

float sampleLightmapChannel(const Image& texels, vec2 uv, int channel) {
    return bilinear(texels, uv, [&](int x, int y) {
        return texels.at(std::clamp(x, 0, texels.width - 1), std::clamp(y, 0, texels.height - 1), channel);
    });
}

Image renderLightmapImage(const CameraReceivers& camera, const TraceScene& trace, const Bvh& bvh,
                          const CameraModel& model, int raysPerAxis, const Scene& scene,
                          const SceneTriangles& triangles, const std::vector<ShippedLightmap>& lightmaps) {
    if (raysPerAxis < 1 || raysPerAxis > 16)
        throw SettingsError("lightmap-image-subsamples: " + std::to_string(raysPerAxis) + " is outside 1..16");
    if (camera.emission.width != model.width || camera.emission.height != model.height)
        throw std::invalid_argument("renderLightmapImage: the receivers are not the camera's");
    // Which lightmap each mesh reads (-1: none, the viewer's unlit level).
    std::vector<int> lightmapOf(scene.meshes.size(), -1);
    for (size_t l = 0; l < lightmaps.size(); ++l)
        for (uint32_t m : lightmaps[l].meshes)
            if (m < scene.meshes.size() && !scene.meshes[m].uv1.empty()) lightmapOf[m] = int(l);

    const TraceSceneView view = trace.view();
    const BvhView bvhView = bvh.view();
    // Lights the lightmaps left out, drawn here per read: exact, or unshadowed times the mask.
    std::vector<uint32_t> engineDrawn;
    for (uint32_t l = 0; l < view.lightCount; ++l)
        if (view.lights[l].engineDrawn) engineDrawn.push_back(l);
    const int strata = DirectLightSettings{}.emitterStrata;
    const int n = raysPerAxis;
    const float weight = 1.0f / float(n * n);
    Image out = camera.emission;
    tbb::parallel_for(tbb::blocked_range<int>(0, model.height), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < model.width; ++x) {
                vec3 reflected(0.0f);
                for (int j = 0; j < n; ++j)
                    for (int i = 0; i < n; ++i) {
                        // The film grid of buildCameraReceivers (receivers/receivers.cpp).
                        const Ray ray = pinholeRay(model, vec2(x + (i + 0.5f) / n, y + (j + 0.5f) / n));
                        Hit hit;
                        if (!intersectClosest(bvhView, ray, hit)) continue;  // the sky: in the emission
                        const SurfaceHit h = surfaceAt(view, hit.triangle, hit.b1, hit.b2);
                        vec3 light(kUnlitLight);
                        const uint32_t m = triangles.meshIndex[hit.triangle];
                        const Image* shadowmask = nullptr;
                        vec2 uv(NAN);
                        if (lightmapOf[m] >= 0) {
                            uv = lightmapUvAt(scene.meshes[m], triangles.localIndex[hit.triangle],
                                              view.vertices + 3 * size_t(hit.triangle), h.position);
                            const ShippedLightmap& lightmap = lightmaps[size_t(lightmapOf[m])];
                            light = sampleLightmap(lightmap.texels, uv);
                            if (!lightmap.shadowmask.empty()) shadowmask = &lightmap.shadowmask;
                        }
                        if (!engineDrawn.empty()) {
                            // The side the camera sees; the read's own seed, so any thread count
                            // gives the same bytes.
                            const bool front = glm::dot(h.geometricNormal, ray.direction) < 0.0f;
                            const vec3 ng = front ? h.geometricNormal : -h.geometricNormal;
                            const vec3 ns = front ? h.shadingNormal : -h.shadingNormal;
                            const uint64_t seed = (uint64_t(y) * uint64_t(model.width) + uint64_t(x)) * uint64_t(n * n) +
                                                  uint64_t(j * n + i);
                            vec3 e(0.0f);
                            for (uint32_t l : engineDrawn) {
                                const TraceLight& drawn = view.lights[l];
                                if (drawn.maskChannel >= 0) {
                                    if (shadowmask)
                                        e += punctualArrival(drawn, h.position, ng, ns, vec2(0.0f)).irradiance *
                                             sampleLightmapChannel(*shadowmask, uv, drawn.maskChannel);
                                    continue;
                                }
                                e += drawn.type == TraceLightType::Directional && drawn.cosHalfAngle < 1.0f
                                         ? sunIrradiance(bvhView, drawn, h.position, ng, ns, strata, seed, l)
                                         : punctualLightIrradiance(bvhView, drawn, h.position, ng, ns, vec2(0.0f));
                            }
                            light += e * kInvPi;
                        }
                        reflected += weight * baseColorAt(view, h) * light;
                    }
                out.setRgb(x, y, out.rgb(x, y) + reflected);
            }
    });
    return out;
}

}  // namespace vl
