#include "trace/path_tracer.h"

#include "core/error.h"
#include "core/progress.h"
#include "trace/bvh.h"
#include "trace/path_elements.h"
#include "trace/trace_scene.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <string>

namespace vl {

void PathTracerSettings::validate() const {
    if (samplesPerPixel < 1)
        throw SettingsError("spp: " + std::to_string(samplesPerPixel) + " is not a positive sample count");
    if (path.maxBounces < 0)
        throw SettingsError("max-bounces: " + std::to_string(path.maxBounces) + " is negative");
    if (path.rouletteStart < 0)
        throw SettingsError("roulette-start: " + std::to_string(path.rouletteStart) + " is negative");
}

namespace {

TraceResult makeResult(int width, int height) {
    TraceResult r;
    r.beauty = Image(width, height, 3);
    r.direct = Image(width, height, 3);
    r.indirect = Image(width, height, 3);
    r.albedo = Image(width, height, 3);
    r.variance = Image(width, height, 3);
    return r;
}

}  // namespace

TraceResult renderCamera(const TraceScene& scene, const Bvh& bvh, const CameraModel& camera,
                         const PathTracerSettings& settings) {
    settings.validate();
    if (camera.width < 1 || camera.height < 1)
        throw SettingsError("image size " + std::to_string(camera.width) + " x " + std::to_string(camera.height) +
                            " is empty");
    const auto start = std::chrono::steady_clock::now();
    TraceResult result = makeResult(camera.width, camera.height);
    const TraceSceneView sv = scene.view();
    const BvhView bv = bvh.view();
    const int spp = settings.samplesPerPixel;
    const PathKernelSettings kernel = pathKernelSettings(settings, kCameraSalt);
    std::atomic<uint64_t> dropped{0};
    Progress progress("render", static_cast<uint64_t>(camera.height), settings.quiet);
    tbb::parallel_for(tbb::blocked_range<int>(0, camera.height, 1), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y) {
            uint64_t rowDropped = 0;
            for (int x = 0; x < camera.width; ++x) {
                const PathEstimate e = cameraPixel(sv, bv, camera, kernel, x, y);
                storeEstimate(result, x, y, e);
                rowDropped += e.dropped;
            }
            if (rowDropped) dropped += rowDropped;
            progress.advance();
        }
    });
    progress.finish();
    result.nonFiniteSamples = dropped.load();
    result.paths = static_cast<uint64_t>(camera.width) * camera.height * spp;
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

TraceResult traceIrradiance(const TraceScene& scene, const Bvh& bvh, const SurfaceSampleSet& receivers,
                            const PathTracerSettings& settings) {
    settings.validate();
    if (receivers.begin.size() != receivers.elementCount() + 1)
        throw Error("traceIrradiance: receiver offsets do not match " + std::to_string(receivers.width) + " x " +
                    std::to_string(receivers.height) + " elements");
    const auto start = std::chrono::steady_clock::now();
    TraceResult result = makeResult(receivers.width, receivers.height);
    const TraceSceneView sv = scene.view();
    const BvhView bv = bvh.view();
    const int spp = settings.samplesPerPixel;
    const PathKernelSettings kernel = pathKernelSettings(settings, kReceiverSalt);
    const size_t elements = receivers.elementCount();
    uint64_t covered = 0;
    for (size_t i = 0; i < elements; ++i) covered += receivers.covered(i) ? 1 : 0;
    std::atomic<uint64_t> dropped{0};
    constexpr size_t kBlock = 256;
    Progress progress("lightmap", elements, settings.quiet);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, elements, kBlock), [&](const tbb::blocked_range<size_t>& range) {
        uint64_t blockDropped = 0;
        for (size_t i = range.begin(); i < range.end(); ++i) {
            const uint32_t count = receivers.sampleCount(i);
            if (count == 0) continue;
            const PathEstimate e =
                receiverElementPaths(sv, bv, receivers.samples.data() + receivers.begin[i], count, i, kernel);
            storeEstimate(result, static_cast<int>(i % receivers.width), static_cast<int>(i / receivers.width), e);
            blockDropped += e.dropped;
        }
        if (blockDropped) dropped += blockDropped;
        progress.advance(range.size());
    });
    progress.finish();
    result.nonFiniteSamples = dropped.load();
    result.paths = covered * static_cast<uint64_t>(spp);
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

}  // namespace vl
