// The voxel direct-lighting launcher: one thread per voxel runs lighting::shadeVoxel.
#include "cuda/device_views.cuh"
#include "cuda/launchers.h"

namespace vl::cuda {

namespace {

template <bool Hierarchical>
__global__ void shadeVoxelsKernel(lighting::LightingView view, uint32_t voxelCount, lighting::VoxelLighting* results,
                                  unsigned long long* counters) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= voxelCount) return;
    lighting::IndexAccessor accessor = view.grid->getAccessor();
    lighting::KernelStats stats;
    results[i] = lighting::shadeVoxel<Hierarchical>(view, accessor, i, stats);
    atomicAdd(&counters[0], static_cast<unsigned long long>(stats.evaluations));
    atomicAdd(&counters[1], static_cast<unsigned long long>(stats.steps));
}

}  // namespace

void shadeVoxelsCuda(const lighting::LightingView& view, uint32_t voxelCount, bool hierarchical,
                     lighting::VoxelLighting* results, lighting::KernelStats& stats) {
    requireDevice();
    if (voxelCount == 0) return;
    if (!view.grid) throw Error("CUDA lighting: the view has no index grid");
    DeviceBuffers buffers;
    const lighting::LightingView device = uploadLighting(buffers, view, voxelCount);
    DeviceArray<lighting::VoxelLighting> deviceResults(voxelCount);
    DeviceArray<unsigned long long> counters(2);
    counters.zero();
    constexpr unsigned kThreads = 128;
    const unsigned blocks = (voxelCount + kThreads - 1) / kThreads;
    if (hierarchical)
        shadeVoxelsKernel<true><<<blocks, kThreads>>>(device, voxelCount, deviceResults.get(), counters.get());
    else
        shadeVoxelsKernel<false><<<blocks, kThreads>>>(device, voxelCount, deviceResults.get(), counters.get());
    finishKernels("voxel lighting kernel");
    deviceResults.copyTo(results);
    const std::vector<unsigned long long> sums = counters.toHost();
    stats.evaluations += sums[0];
    stats.steps += sums[1];
}

LightingStats lightVoxelsCuda(const Scene& scene, VoxelScene& voxels, const LightingSettings& settings) {
    requireDevice();
    return lightVoxels(scene, voxels, settings, nullptr, &shadeVoxelsCuda);
}

}  // namespace vl::cuda
