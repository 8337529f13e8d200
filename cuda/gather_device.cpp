#include "cuda/launchers.h"

namespace vl::cuda {
namespace {

class CudaGatherDevice final : public GatherDevice {
public:
    std::vector<vec3> gatherCones(const std::vector<GatherPoint>& points, const MipView& mips, const ConeSettings& cone,
                                  int turns) const override {
        return gatherIrradianceCuda(points, mips, cone, turns);
    }
    ReceiverLighting shadeReceivers(const SurfaceSampleSet& receivers, const TraceSceneView& scene, const BvhView& bvh,
                                    const MipView* mips, const IrradianceCacheView* cache, const ConeSettings& cone,
                                    const DirectLightSettings& direct, bool mayBeBuried) const override {
        return shadeReceiversCuda(receivers, scene, bvh, mips, cache, cone, direct, mayBeBuried);
    }
};

}  // namespace

const GatherDevice& gatherDevice() {
    static const CudaGatherDevice device;
    return device;
}

}  // namespace vl::cuda
