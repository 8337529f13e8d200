#include "gather/shadowmask.h"

#include "lighting/direct_light.h"
#include "scene/scene.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace vl {

bool hasShadowmaskLights(const TraceSceneView& scene) {
    for (uint32_t l = 0; l < scene.lightCount; ++l)
        if (scene.lights[l].maskChannel >= 0) return true;
    return false;
}

Image shadowmaskTexels(const SurfaceSampleSet& receivers, const TraceSceneView& scene, const BvhView& bvh,
                       size_t firstElement, size_t lastElement) {
    if (!hasShadowmaskLights(scene)) return Image();
    Image mask(receivers.width, receivers.height, kShadowmaskChannels);
    bool used[kShadowmaskChannels] = {};
    for (uint32_t l = 0; l < scene.lightCount; ++l)
        if (scene.lights[l].maskChannel >= 0) used[scene.lights[l].maskChannel] = true;
    const size_t elements = std::min(receivers.elementCount(), lastElement);
    tbb::parallel_for(tbb::blocked_range<size_t>(std::min(firstElement, elements), elements, 64),
                      [&](const tbb::blocked_range<size_t>& range) {
                          for (size_t e = range.begin(); e != range.end(); ++e) {
                              float facing[kShadowmaskChannels] = {}, seen[kShadowmaskChannels] = {};
                              for (uint32_t k = receivers.begin[e]; k < receivers.begin[e + 1]; ++k) {
                                  const SurfaceSample& r = receivers.samples[k];
                                  const vec3* v = scene.vertices + 3 * size_t(r.triangle);
                                  vec3 ng = glm::normalize(glm::cross(v[1] - v[0], v[2] - v[0]));
                                  if (glm::dot(ng, r.normal) < 0.0f) ng = -ng;
                                  for (uint32_t l = 0; l < scene.lightCount; ++l) {
                                      const TraceLight& light = scene.lights[l];
                                      if (light.maskChannel < 0) continue;
                                      // The cosine toward the light's centre, 0 under either horizon.
                                      const vec3 toLight = light.type == TraceLightType::Directional
                                                               ? -light.direction
                                                               : glm::normalize(light.position - r.position);
                                      const float cosine =
                                          glm::dot(ng, toLight) > 0.0f ? glm::max(glm::dot(r.normal, toLight), 0.0f) : 0.0f;
                                      if (!(cosine > 0.0f)) continue;
                                      facing[light.maskChannel] += r.weight * cosine;
                                      seen[light.maskChannel] += r.weight * cosine *
                                          lightVisibility(bvh, light, r.position, ng, kShadowmaskStrata, k, l);
                                  }
                              }
                              for (int c = 0; c < kShadowmaskChannels; ++c)
                                  mask.pixels[e * kShadowmaskChannels + size_t(c)] =
                                      !used[c]            ? 1.0f
                                      : facing[c] > 0.0f ? std::min(1.0f, seen[c] / facing[c])
                                                          : kShadowmaskUnseen;
                          }
                      });
    return mask;
}

}  // namespace vl
