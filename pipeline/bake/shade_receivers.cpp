#include "bake/shade_receivers.h"

#include "cone/cone_set.h"
#include "cone/cone_trace.h"
#include "core/progress.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace vl {

ReceiverLighting shadeReceivers(const SurfaceSampleSet& receivers, const TraceSceneView& scene, const BvhView& bvh,
                                const MipView* mips, const ConeSettings& cone, const DirectLightSettings& direct,
                                Progress* progress) {
    ReceiverLighting out;
    for (Image* image : {&out.direct, &out.indirect, &out.directRadiance, &out.indirectRadiance})
        *image = Image(receivers.width, receivers.height, 3);
    const ConeSet& set = coneSet(cone.coneCount);
    const size_t elements = receivers.elementCount();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, elements, 64), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t e = range.begin(); e != range.end(); ++e) {
            vec3 directSum(0.0f), indirectSum(0.0f), directReflected(0.0f), indirectReflected(0.0f);
            for (uint32_t i = receivers.begin[e]; i < receivers.begin[e + 1]; ++i) {
                const SurfaceSample& r = receivers.samples[i];
                const vec3 ed = directIrradiance(scene, bvh, r, direct, i) * kInvPi;
                const vec3 ei = mips ? coneTraceIrradiance(*mips, r.position, r.normal, set, cone) * kInvPi : vec3(0.0f);
                directSum += r.weight * ed;
                indirectSum += r.weight * ei;
                directReflected += r.weight * r.albedo * ed;
                indirectReflected += r.weight * r.albedo * ei;
            }
            const int x = static_cast<int>(e % static_cast<size_t>(receivers.width));
            const int y = static_cast<int>(e / static_cast<size_t>(receivers.width));
            out.direct.setRgb(x, y, directSum);
            out.indirect.setRgb(x, y, indirectSum);
            out.directRadiance.setRgb(x, y, directReflected);
            out.indirectRadiance.setRgb(x, y, indirectReflected);
        }
        if (progress) progress->advance(range.size());
    });
    return out;
}

}  // namespace vl
