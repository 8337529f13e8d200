#include "bake/lightmap_image.h"

#include "export/lightmap_encoding.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace vl {

namespace {

vec3 texel(const Image& image, int x, int y) {
    x = std::clamp(x, 0, image.width - 1);
    y = std::clamp(y, 0, image.height - 1);
    return image.rgb(x, y);
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

vec3 sampleLightmap(const Image& texels, vec2 uv) {
    if (texels.empty() || !std::isfinite(uv.x) || !std::isfinite(uv.y)) return vec3(0.0f);
    // Far outside the image every texel clamps to the edge: keep the float → int exact.
    const float px = std::clamp(uv.x * float(texels.width) - 0.5f, -1.0f, float(texels.width));
    const float py = std::clamp(uv.y * float(texels.height) - 0.5f, -1.0f, float(texels.height));
    const float fx0 = std::floor(px), fy0 = std::floor(py);
    const int x0 = int(fx0), y0 = int(fy0);
    const float ax = px - fx0, ay = py - fy0;
    const vec3 top = glm::mix(texel(texels, x0, y0), texel(texels, x0 + 1, y0), ax);
    const vec3 bottom = glm::mix(texel(texels, x0, y0 + 1), texel(texels, x0 + 1, y0 + 1), ax);
    return glm::mix(top, bottom, ay);
}

Image renderLightmapImage(const CameraReceivers& camera, const Scene& scene, const SceneTriangles& triangles,
                          const std::vector<ShippedLightmap>& lightmaps) {
    // Which lightmap each mesh reads (-1: none, the viewer's unlit level).
    std::vector<int> lightmapOf(scene.meshes.size(), -1);
    for (size_t l = 0; l < lightmaps.size(); ++l)
        for (uint32_t m : lightmaps[l].meshes)
            if (m < scene.meshes.size() && !scene.meshes[m].uv1.empty()) lightmapOf[m] = int(l);

    const SurfaceSampleSet& receivers = camera.receivers;
    Image out = camera.emission;
    tbb::parallel_for(tbb::blocked_range<int>(0, receivers.height), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < receivers.width; ++x) {
                const size_t element = size_t(y) * size_t(receivers.width) + size_t(x);
                vec3 reflected(0.0f);
                for (uint32_t k = receivers.begin[element]; k < receivers.begin[element + 1]; ++k) {
                    const SurfaceSample& s = receivers.samples[k];
                    vec3 light(kUnlitLight);
                    if (s.triangle < triangles.meshIndex.size()) {
                        const uint32_t m = triangles.meshIndex[s.triangle];
                        if (lightmapOf[m] >= 0) {
                            const vec2 uv = lightmapUvAt(scene.meshes[m], triangles.localIndex[s.triangle],
                                                  &triangles.vertices[3 * size_t(s.triangle)], s.position);
                            light = sampleLightmap(lightmaps[size_t(lightmapOf[m])].texels, uv);
                        }
                    }
                    reflected += s.weight * s.albedo * light;
                }
                out.setRgb(x, y, out.rgb(x, y) + reflected);
            }
    });
    return out;
}

}  // namespace vl
