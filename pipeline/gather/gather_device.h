// The gather's kernels a device may run in the CPU's stead: cuda/ implements them
// (cuda/launchers.h gatherDevice), the same VL_HOSTDEV kernels over the same views. A gather
// given no device runs them on the CPU. The device's results agree with the CPU's within the
// bounds cuda/launchers.h states, not to the bit.
#pragma once

#include "gather/irradiance_cache.h"
#include "gather/shade_receivers.h"

#include <vector>

namespace vl {

class GatherDevice {
public:
    virtual ~GatherDevice() = default;
    // The cone-traced irradiance at every point: IrradianceCache::gather's.
    virtual std::vector<vec3> gatherCones(const std::vector<GatherPoint>& points, const MipView& mips,
                                          const ConeSettings& cone, int turns) const = 0;
    // shadeReceivers of every element.
    virtual ReceiverLighting shadeReceivers(const SurfaceSampleSet& receivers, const TraceSceneView& scene,
                                            const BvhView& bvh, const MipView* mips, const IrradianceCacheView* cache,
                                            const ConeSettings& cone, const DirectLightSettings& direct,
                                            bool mayBeBuried) const = 0;
};

}  // namespace vl
