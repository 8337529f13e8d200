#include "trace/path_tracer.h"

#include "core/error.h"
#include "core/progress.h"
#include "trace/bvh.h"
#include "trace/sample_patterns.h"
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

// Running sums of one element's samples, in double so the mean does not depend on the
// order of summation at thread boundaries (there are none: one element, one thread).
struct Accumulator {
    glm::dvec3 beauty{0.0}, beautySq{0.0}, direct{0.0}, indirect{0.0}, albedo{0.0};
    uint32_t dropped = 0;

    void add(const PathSample& s) {
        const vec3 total = s.direct + s.indirect;
        if (!isFinite(total) || !isFinite(s.albedo)) {
            ++dropped;  // counted as a zero sample: keeps the estimator's divisor
            return;
        }
        const glm::dvec3 t(total);
        beauty += t;
        beautySq += t * t;
        direct += glm::dvec3(s.direct);
        indirect += glm::dvec3(s.indirect);
        albedo += glm::dvec3(s.albedo);
    }

    void store(TraceResult& r, int x, int y, int n) const {
        const double inv = 1.0 / n;
        const glm::dvec3 mean = beauty * inv;
        glm::dvec3 var(0.0);
        if (n > 1) var = glm::max(glm::dvec3(0.0), (beautySq - beauty * mean) / (double(n) * (n - 1)));
        r.beauty.setRgb(x, y, vec3(mean));
        r.direct.setRgb(x, y, vec3(direct * inv));
        r.indirect.setRgb(x, y, vec3(indirect * inv));
        r.albedo.setRgb(x, y, vec3(albedo * inv));
        r.variance.setRgb(x, y, vec3(var));
    }
};

TraceResult makeResult(int width, int height) {
    TraceResult r;
    r.beauty = Image(width, height, 3);
    r.direct = Image(width, height, 3);
    r.indirect = Image(width, height, 3);
    r.albedo = Image(width, height, 3);
    r.variance = Image(width, height, 3);
    return r;
}

// Salts keep camera and receiver streams apart even for the same element index.
constexpr uint64_t kCameraSalt = 0x63616d657261ull;
constexpr uint64_t kReceiverSalt = 0x7265636569766572ull;
// The "sample number" that seeds a pixel's pattern rotation, apart from every real sample.
constexpr uint64_t kPatternSample = ~0ull;

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
    const uint64_t salt = settings.seed ^ kCameraSalt;
    std::atomic<uint64_t> dropped{0};
    Progress progress("render", static_cast<uint64_t>(camera.height), settings.quiet);
    tbb::parallel_for(tbb::blocked_range<int>(0, camera.height, 1), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y) {
            uint64_t rowDropped = 0;
            for (int x = 0; x < camera.width; ++x) {
                const uint64_t index = static_cast<uint64_t>(y) * camera.width + x;
                // The pixel's rotation of its stratified pixel and lens patterns.
                Pcg32 patternRng = Pcg32::forItem(index, kPatternSample, salt);
                const vec2 pixelShift(patternRng.next1D(), patternRng.next1D());
                const vec2 lensShift(patternRng.next1D(), patternRng.next1D());
                Accumulator acc;
                for (int j = 0; j < spp; ++j) {
                    Pcg32 rng = Pcg32::forItem(index, static_cast<uint64_t>(j), salt);
                    const vec2 uPixel = rotatedHammersley(static_cast<uint32_t>(j), static_cast<uint32_t>(spp), pixelShift);
                    const vec2 uLens = rotatedHalton35(static_cast<uint32_t>(j), lensShift);
                    const Ray ray = thinLensRay(camera, pixelSamplePoint(x, y, uPixel, settings.filter), uLens);
                    acc.add(traceCameraPath(sv, bv, ray, rng, settings.path));
                }
                acc.store(result, x, y, spp);
                rowDropped += acc.dropped;
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
    const uint64_t salt = settings.seed ^ kReceiverSalt;
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
            const SurfaceSample* samples = receivers.samples.data() + receivers.begin[i];
            double totalWeight = 0.0;
            for (uint32_t k = 0; k < count; ++k) totalWeight += samples[k].weight;
            Accumulator acc;
            uint32_t k = 0;
            double cumulative = samples[0].weight;
            for (int j = 0; j < spp; ++j) {
                // Sample j goes to the receiver sample whose cumulative weight interval holds
                // (j + ½)/spp: each gets a share of the spp in proportion to its weight
                // (stratified, deterministic). Past the weights' sum lies the background.
                const double t = (j + 0.5) / spp;
                while (t >= cumulative && k + 1 < count) cumulative += samples[++k].weight;
                const bool background = t >= cumulative && totalWeight < 1.0 - 1e-5;
                if (background) {
                    acc.add(PathSample{});
                    continue;
                }
                Pcg32 rng = Pcg32::forItem(i, static_cast<uint64_t>(j), salt);
                acc.add(traceReceiverPath(sv, bv, samples[k], rng, settings.path));
            }
            acc.store(result, static_cast<int>(i % receivers.width), static_cast<int>(i / receivers.width), spp);
            blockDropped += acc.dropped;
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
