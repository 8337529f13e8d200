// The path-tracing launchers: thread (x, y) = (blockIdx·blockDim + threadIdx) per axis
// (ERRATA eq. 7–8) traces every sample of pixel or texel (x, y), seeded as on the CPU.
#include "cuda/device_views.cuh"
#include "cuda/launchers.h"
#include "trace/path_elements.h"

#include <chrono>

namespace vl::cuda {

namespace {

__global__ void cameraKernel(TraceSceneView scene, BvhView bvh, CameraModel camera, PathKernelSettings settings,
                             PathEstimate* out) {
    const int x = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
    const int y = static_cast<int>(blockIdx.y * blockDim.y + threadIdx.y);
    if (x >= camera.width || y >= camera.height) return;
    out[static_cast<size_t>(y) * static_cast<size_t>(camera.width) + static_cast<size_t>(x)] =
        cameraPixel(scene, bvh, camera, settings, x, y);
}

__global__ void receiverKernel(TraceSceneView scene, BvhView bvh, const uint32_t* begin, const SurfaceSample* samples,
                               int width, int height, PathKernelSettings settings, PathEstimate* out) {
    const int x = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
    const int y = static_cast<int>(blockIdx.y * blockDim.y + threadIdx.y);
    if (x >= width || y >= height) return;
    const size_t e = static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x);
    out[e] = receiverElementPaths(scene, bvh, samples + begin[e], begin[e + 1] - begin[e], e, settings);
}

TraceResult collect(const std::vector<PathEstimate>& estimates, int width, int height) {
    TraceResult r;
    for (Image* image : {&r.beauty, &r.direct, &r.indirect, &r.albedo, &r.variance}) *image = Image(width, height, 3);
    for (size_t e = 0; e < estimates.size(); ++e) {
        const int x = static_cast<int>(e % static_cast<size_t>(width));
        const int y = static_cast<int>(e / static_cast<size_t>(width));
        storeEstimate(r, x, y, estimates[e]);
        r.nonFiniteSamples += estimates[e].dropped;
    }
    return r;
}

double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

TraceResult renderCameraCuda(const TraceScene& scene, const Bvh& bvh, const CameraModel& camera,
                             const PathTracerSettings& settings) {
    settings.validate();
    if (camera.width < 1 || camera.height < 1)
        throw SettingsError("image size " + std::to_string(camera.width) + " x " + std::to_string(camera.height) +
                            " is empty");
    requireDevice();
    const auto start = std::chrono::steady_clock::now();
    DeviceBuffers buffers;
    const TraceSceneView deviceScene = uploadTraceScene(buffers, scene.view());
    const BvhView deviceBvh = uploadBvh(buffers, bvh.view());
    const size_t pixels = static_cast<size_t>(camera.width) * static_cast<size_t>(camera.height);
    DeviceArray<PathEstimate> results(pixels);
    const dim3 threads(16, 8);
    cameraKernel<<<imageBlocks(camera.width, camera.height, threads), threads>>>(
        deviceScene, deviceBvh, camera, pathKernelSettings(settings, kCameraSalt), results.get());
    finishKernels("camera path-tracing kernel");
    TraceResult r = collect(results.toHost(), camera.width, camera.height);
    r.paths = static_cast<uint64_t>(pixels) * static_cast<uint64_t>(settings.samplesPerPixel);
    r.seconds = secondsSince(start);
    return r;
}

TraceResult traceIrradianceCuda(const TraceScene& scene, const Bvh& bvh, const SurfaceSampleSet& receivers,
                                const PathTracerSettings& settings) {
    settings.validate();
    if (receivers.begin.size() != receivers.elementCount() + 1)
        throw Error("traceIrradiance: receiver offsets do not match " + std::to_string(receivers.width) + " x " +
                    std::to_string(receivers.height) + " elements");
    requireDevice();
    const auto start = std::chrono::steady_clock::now();
    const size_t elements = receivers.elementCount();
    if (elements == 0) return collect({}, receivers.width, receivers.height);
    DeviceBuffers buffers;
    const TraceSceneView deviceScene = uploadTraceScene(buffers, scene.view());
    const BvhView deviceBvh = uploadBvh(buffers, bvh.view());
    const DeviceArray<uint32_t> begin(receivers.begin);
    const DeviceArray<SurfaceSample> samples(receivers.samples);
    DeviceArray<PathEstimate> results(elements);
    const dim3 threads(16, 8);
    receiverKernel<<<imageBlocks(receivers.width, receivers.height, threads), threads>>>(
        deviceScene, deviceBvh, begin.get(), samples.get(), receivers.width, receivers.height,
        pathKernelSettings(settings, kReceiverSalt), results.get());
    finishKernels("lightmap path-tracing kernel");
    TraceResult r = collect(results.toHost(), receivers.width, receivers.height);
    uint64_t covered = 0;
    for (size_t i = 0; i < elements; ++i) covered += receivers.covered(i) ? 1 : 0;
    r.paths = covered * static_cast<uint64_t>(settings.samplesPerPixel);
    r.seconds = secondsSince(start);
    return r;
}

}  // namespace vl::cuda
