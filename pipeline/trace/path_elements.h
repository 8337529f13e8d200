// One pixel or receiver element of the path tracer (ERRATA eq. 7–8: a thread per element),
// written once for renderCamera / traceIrradiance (TBB) and the CUDA launchers: each
// element seeds its own generators from its index and sample number, so the result does not
// depend on the thread count or the device's launch shape.
#pragma once

#include "trace/camera.h"
#include "trace/path_kernels.h"
#include "trace/path_tracer.h"
#include "trace/sample_patterns.h"
#include "trace/surface_samples.h"

#include <cstdint>

namespace vl {

// Salts keep camera and receiver streams apart even for the same element index; the
// "sample number" kPatternSample seeds a pixel's pattern rotation, apart from every real sample.
constexpr uint64_t kCameraSalt = 0x63616d657261ull;
constexpr uint64_t kReceiverSalt = 0x7265636569766572ull;
constexpr uint64_t kPatternSample = ~0ull;

// One element's estimate: what TraceResult's images hold at its pixel (storeEstimate).
struct PathEstimate {
    vec3 beauty{0.0f};
    vec3 direct{0.0f};
    vec3 indirect{0.0f};
    vec3 albedo{0.0f};
    vec3 variance{0.0f};
    uint32_t dropped = 0;
};

// The running sums of one element's samples, in double so the mean does not depend on the
// order of summation. A non-finite sample counts as zero (it keeps the estimator's divisor).
struct PathAccumulator {
    glm::dvec3 beauty{0.0}, beautySq{0.0}, direct{0.0}, indirect{0.0}, albedo{0.0};
    uint32_t dropped = 0;

    VL_HOSTDEV void add(const PathSample& s) {
        const vec3 total = s.direct + s.indirect;
        if (!isFinite(total) || !isFinite(s.albedo)) {
            ++dropped;
            return;
        }
        const glm::dvec3 t(total);
        beauty += t;
        beautySq += t * t;
        direct += glm::dvec3(s.direct);
        indirect += glm::dvec3(s.indirect);
        albedo += glm::dvec3(s.albedo);
    }

    VL_HOSTDEV PathEstimate finish(int n) const {
        const double inv = 1.0 / n;
        const glm::dvec3 mean = beauty * inv;
        glm::dvec3 var(0.0);
        if (n > 1) var = glm::max(glm::dvec3(0.0), (beautySq - beauty * mean) / (double(n) * (n - 1)));
        PathEstimate e;
        e.beauty = vec3(mean);
        e.direct = vec3(direct * inv);
        e.indirect = vec3(indirect * inv);
        e.albedo = vec3(albedo * inv);
        e.variance = vec3(var);
        e.dropped = dropped;
        return e;
    }
};

// The settings an element reads (PathTracerSettings without its host-only parts).
struct PathKernelSettings {
    int samplesPerPixel = 1;
    PathSettings path;
    PixelFilter filter = PixelFilter::Tent;
    uint64_t salt = 0;  // settings.seed ^ kCameraSalt or ^ kReceiverSalt
};

// Camera pixel (x, y): spp thin-lens paths from the pixel's rotated stratified patterns.
VL_HOSTDEV inline PathEstimate cameraPixel(const TraceSceneView& scene, const BvhView& bvh, const CameraModel& camera,
                                           const PathKernelSettings& settings, int x, int y) {
    const uint64_t index = static_cast<uint64_t>(y) * static_cast<uint64_t>(camera.width) + static_cast<uint64_t>(x);
    Pcg32 patternRng = Pcg32::forItem(index, kPatternSample, settings.salt);
    vec2 pixelShift, lensShift;
    patternRng.next2D(pixelShift.x, pixelShift.y);
    patternRng.next2D(lensShift.x, lensShift.y);
    const int spp = settings.samplesPerPixel;
    PathAccumulator acc;
    for (int j = 0; j < spp; ++j) {
        Pcg32 rng = Pcg32::forItem(index, static_cast<uint64_t>(j), settings.salt);
        const vec2 uPixel = rotatedHammersley(static_cast<uint32_t>(j), static_cast<uint32_t>(spp), pixelShift);
        const vec2 uLens = rotatedHalton35(static_cast<uint32_t>(j), lensShift);
        const Ray ray = thinLensRay(camera, pixelSamplePoint(x, y, uPixel, settings.filter), uLens);
        acc.add(traceCameraPath(scene, bvh, ray, rng, settings.path));
    }
    return acc.finish(spp);
}

// Receiver element `element` with samples [samples, samples + count): E/π by white-receiver
// paths. Sample j goes to the receiver sample whose cumulative weight interval holds
// (j + ½)/spp: each gets a share of the spp in proportion to its weight (stratified,
// deterministic); past the weights' sum lies the background. count 0: zero.
VL_HOSTDEV inline PathEstimate receiverElementPaths(const TraceSceneView& scene, const BvhView& bvh,
                                                    const SurfaceSample* samples, uint32_t count, uint64_t element,
                                                    const PathKernelSettings& settings) {
    if (count == 0) return PathEstimate{};
    double totalWeight = 0.0;
    for (uint32_t k = 0; k < count; ++k) totalWeight += samples[k].weight;
    const int spp = settings.samplesPerPixel;
    PathAccumulator acc;
    uint32_t k = 0;
    double cumulative = samples[0].weight;
    for (int j = 0; j < spp; ++j) {
        const double t = (j + 0.5) / spp;
        while (t >= cumulative && k + 1 < count) cumulative += samples[++k].weight;
        const bool background = t >= cumulative && totalWeight < 1.0 - 1e-5;
        if (background) {
            acc.add(PathSample{});
            continue;
        }
        Pcg32 rng = Pcg32::forItem(element, static_cast<uint64_t>(j), settings.salt);
        acc.add(traceReceiverPath(scene, bvh, samples[k], rng, settings.path));
    }
    return acc.finish(spp);
}

inline PathKernelSettings pathKernelSettings(const PathTracerSettings& settings, uint64_t salt) {
    PathKernelSettings k;
    k.samplesPerPixel = settings.samplesPerPixel;
    k.path = settings.path;
    k.filter = settings.filter;
    k.salt = settings.seed ^ salt;
    return k;
}

inline void storeEstimate(TraceResult& result, int x, int y, const PathEstimate& e) {
    result.beauty.setRgb(x, y, e.beauty);
    result.direct.setRgb(x, y, e.direct);
    result.indirect.setRgb(x, y, e.indirect);
    result.albedo.setRgb(x, y, e.albedo);
    result.variance.setRgb(x, y, e.variance);
}

}  // namespace vl
