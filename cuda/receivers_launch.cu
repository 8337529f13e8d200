// The bake receivers launcher: thread (x, y) shades element (x, y) of the receiver image
// (exact direct light through the BVH, indirect light interpolated from the gather points or
// by cones through the radiance mips), and the gather points' own cone gather.
#include "cuda/device_views.cuh"
#include "gather/shade_element.h"
#include "cuda/launchers.h"

namespace vl::cuda {

namespace {

__global__ void shadeReceiversKernel(TraceSceneView scene, BvhView bvh, MipView mips, int hasMips,
                                     IrradianceCacheView cache, int hasCache, ConeSet set, ConeSettings cone,
                                     DirectLightSettings direct, int mayBeBuried, const uint32_t* begin,
                                     const SurfaceSample* samples, int width, int height, ElementLighting* out) {
    const int x = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
    const int y = static_cast<int>(blockIdx.y * blockDim.y + threadIdx.y);
    if (x >= width || y >= height) return;
    const size_t e = static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x);
    out[e] = shadeReceiverElement(scene, bvh, hasMips ? &mips : nullptr, hasCache ? &cache : nullptr, set, cone, direct,
                                  samples, begin[e], begin[e + 1], mayBeBuried != 0);
}

__global__ void gatherIrradianceKernel(MipView mips, ConeSet set, ConeSettings cone, int turns,
                                       const GatherPoint* points, uint32_t count, vec3* out) {
    const uint32_t q = blockIdx.x * blockDim.x + threadIdx.x;
    if (q >= count) return;
    out[q] = gatherAtPoint(mips, points[q], set, cone, turns);
}

}  // namespace

ReceiverLighting shadeReceiversCuda(const SurfaceSampleSet& receivers, const TraceSceneView& scene,
                                    const BvhView& bvh, const MipView* mips, const IrradianceCacheView* cache,
                                    const ConeSettings& cone, const DirectLightSettings& direct, bool mayBeBuried) {
    requireDevice();
    const size_t elements = receivers.elementCount();
    if (receivers.begin.size() != elements + 1)
        throw Error("CUDA receivers: offsets do not match " + std::to_string(receivers.width) + " x " +
                    std::to_string(receivers.height) + " elements");
    ReceiverLighting out;
    for (Image* image : {&out.direct, &out.indirect, &out.directRadiance, &out.indirectRadiance})
        *image = Image(receivers.width, receivers.height, 3);
    if (mayBeBuried) out.open = Image(receivers.width, receivers.height, 1);
    if (elements == 0) return out;

    DeviceBuffers buffers;
    const TraceSceneView deviceScene = uploadTraceScene(buffers, scene);
    const BvhView deviceBvh = uploadBvh(buffers, bvh);
    const MipView deviceMips = mips ? uploadMips(buffers, *mips) : MipView{};
    const IrradianceCacheView deviceCache = cache ? uploadCache(buffers, *cache, deviceMips) : IrradianceCacheView{};
    const DeviceArray<uint32_t> begin(receivers.begin);
    const DeviceArray<SurfaceSample> samples(receivers.samples);
    DeviceArray<ElementLighting> results(elements);

    const dim3 threads(16, 8);
    shadeReceiversKernel<<<imageBlocks(receivers.width, receivers.height, threads), threads>>>(
        deviceScene, deviceBvh, deviceMips, mips ? 1 : 0, deviceCache, cache ? 1 : 0, coneSet(cone.coneCount), cone, direct,
        mayBeBuried ? 1 : 0, begin.get(), samples.get(), receivers.width, receivers.height, results.get());
    finishKernels("receiver shading kernel");

    const std::vector<ElementLighting> host = results.toHost();
    for (size_t e = 0; e < elements; ++e) {
        const int x = static_cast<int>(e % static_cast<size_t>(receivers.width));
        const int y = static_cast<int>(e / static_cast<size_t>(receivers.width));
        out.direct.setRgb(x, y, host[e].direct);
        out.indirect.setRgb(x, y, host[e].indirect);
        out.directRadiance.setRgb(x, y, host[e].directRadiance);
        out.indirectRadiance.setRgb(x, y, host[e].indirectRadiance);
        if (mayBeBuried) out.open.at(x, y) = host[e].openWeight;
    }
    return out;
}

std::vector<vec3> gatherIrradianceCuda(const std::vector<GatherPoint>& points, const MipView& mips,
                                       const ConeSettings& cone, int turns) {
    requireDevice();
    if (turns < 1 || turns > kMaxGatherTurns)
        throw SettingsError("gather turns " + std::to_string(turns) + " is outside 1.." + std::to_string(kMaxGatherTurns));
    if (points.empty()) return {};
    DeviceBuffers buffers;
    const MipView deviceMips = uploadMips(buffers, mips);
    const DeviceArray<GatherPoint> devicePoints(points);
    DeviceArray<vec3> results(points.size());
    const uint32_t count = static_cast<uint32_t>(points.size());
    constexpr uint32_t kThreads = 128;
    gatherIrradianceKernel<<<(count + kThreads - 1) / kThreads, kThreads>>>(deviceMips, coneSet(cone.coneCount), cone,
                                                                            turns, devicePoints.get(), count, results.get());
    finishKernels("irradiance gather kernel");
    return results.toHost();
}

}  // namespace vl::cuda
