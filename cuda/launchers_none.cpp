// The build without a CUDA compiler: every launcher says why there is no GPU.
#include "core/error.h"
#include "cuda/device.h"
#include "cuda/launchers.h"

namespace vl::cuda {

namespace {

[[noreturn]] void noDevice() { throw Error("CUDA: " + probeDevice().description); }

}  // namespace

void shadeVoxelsCuda(const lighting::LightingView&, uint32_t, bool, lighting::VoxelLighting*, lighting::KernelStats&) {
    noDevice();
}

LightingStats lightVoxelsCuda(const Scene&, VoxelScene&, const LightingSettings&) { noDevice(); }

ReceiverLighting shadeReceiversCuda(const SurfaceSampleSet&, const TraceSceneView&, const BvhView&, const MipView*,
                                    const IrradianceCacheView*, const ConeSettings&, const DirectLightSettings&, bool) {
    noDevice();
}

std::vector<vec3> gatherIrradianceCuda(const std::vector<GatherPoint>&, const MipView&, const ConeSettings&, int) {
    noDevice();
}

TraceResult renderCameraCuda(const TraceScene&, const Bvh&, const CameraModel&, const PathTracerSettings&) {
    noDevice();
}

TraceResult traceIrradianceCuda(const TraceScene&, const Bvh&, const SurfaceSampleSet&, const PathTracerSettings&) {
    noDevice();
}

}  // namespace vl::cuda
