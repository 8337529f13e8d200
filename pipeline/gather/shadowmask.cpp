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
                              float weight = 0.0f, seen[kShadowmaskChannels] = {};
                              for (uint32_t k = receivers.begin[e]; k < receivers.begin[e + 1]; ++k) {
                                  const SurfaceSample& r = receivers.samples[k];
                                  const vec3* v = scene.vertices + 3 * size_t(r.triangle);
                                  vec3 ng = glm::normalize(glm::cross(v[1] - v[0], v[2] - v[0]));
                                  if (glm::dot(ng, r.normal) < 0.0f) ng = -ng;
                                  for (uint32_t l = 0; l < scene.lightCount; ++l) {
                                      const TraceLight& light = scene.lights[l];
                                      if (light.maskChannel < 0) continue;
                                      seen[light.maskChannel] +=
                                          r.weight * lightVisibility(bvh, light, r.position, ng, kShadowmaskStrata, k, l);
                                  }
                                  weight += r.weight;
                              }
                              for (int c = 0; c < kShadowmaskChannels; ++c)
                                  mask.pixels[e * kShadowmaskChannels + size_t(c)] =
                                      !used[c] ? 1.0f : weight > 0.0f ? std::min(1.0f, seen[c] / weight) : 0.0f;
                          }
                      });
    return mask;
}

}  // namespace vl
