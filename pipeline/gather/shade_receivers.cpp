#include "gather/shade_receivers.h"

#include "gather/shade_element.h"
#include "core/progress.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace vl {

ReceiverLighting shadeReceivers(const SurfaceSampleSet& receivers, const TraceSceneView& scene, const BvhView& bvh,
                                const MipView* mips, const IrradianceCacheView* cache, const ConeSettings& cone,
                                const DirectLightSettings& direct, bool mayBeBuried, Progress* progress,
                                size_t firstElement, size_t lastElement) {
    ReceiverLighting out;
    for (Image* image : {&out.direct, &out.indirect, &out.directRadiance, &out.indirectRadiance})
        *image = Image(receivers.width, receivers.height, 3);
    if (mayBeBuried) out.open = Image(receivers.width, receivers.height, 1);
    const ConeSet& set = coneSet(cone.coneCount);
    const size_t elements = std::min(receivers.elementCount(), lastElement);
    tbb::parallel_for(tbb::blocked_range<size_t>(std::min(firstElement, elements), elements, 64), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t e = range.begin(); e != range.end(); ++e) {
            const ElementLighting lit = shadeReceiverElement(scene, bvh, mips, cache, set, cone, direct,
                                                             receivers.samples.data(), receivers.begin[e],
                                                             receivers.begin[e + 1], mayBeBuried);
            const int x = static_cast<int>(e % static_cast<size_t>(receivers.width));
            const int y = static_cast<int>(e / static_cast<size_t>(receivers.width));
            out.direct.setRgb(x, y, lit.direct);
            out.indirect.setRgb(x, y, lit.indirect);
            out.directRadiance.setRgb(x, y, lit.directRadiance);
            out.indirectRadiance.setRgb(x, y, lit.indirectRadiance);
            if (mayBeBuried) out.open.at(x, y) = lit.openWeight;
        }
        if (progress) progress->advance(range.size());
    });
    return out;
}

}  // namespace vl
